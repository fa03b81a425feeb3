//! Bad input never panics and never silently runs: every malformed input gets an error
//! naming the file and the line or field.

use std::path::Path;
use sticky_lips::element::hex8::GradientVariant;
use sticky_lips::io::{niftysim, scenario};

const GOOD_XML: &str = r#"<?xml version="1.0"?>
<Model>
   <Nodes DOF="3" NumNodes="8">
      0.0 0.0 0.0
      0.01 0.0 0.0
      0.01 0.01 0.0
      0.0 0.01 0.0
      0.0 0.0 0.01
      0.01 0.0 0.01
      0.01 0.01 0.01
      0.0 0.01 0.01
   </Nodes>
   <Elements NumEls="1" Type="H8">
      0 1 2 3 4 5 6 7
   </Elements>
   <ElementSet Size="1">
      <Material Type="NH">
         <ElasticParams NumParams="2">
            1000.0 10000.0
         </ElasticParams>
      </Material>
      0
   </ElementSet>
   <Constraint DOF="all" NumNodes="4" Type="Fix">
      <Nodes>
         0 1 2 3
      </Nodes>
   </Constraint>
   <SystemParams>
      <TimeStep>0.0001</TimeStep>
      <TotalTime>0.01</TotalTime>
      <DampingCoeff>50.0</DampingCoeff>
      <Density>1000.0</Density>
   </SystemParams>
</Model>
"#;

fn xml_err(text: &str) -> String {
    let r = niftysim::parse(text, "model.xml", GradientVariant::MeanGradient, false)
        .and_then(|p| p.validate().map(|_| p));
    match r {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn good_xml_is_accepted() {
    let p = niftysim::parse(GOOD_XML, "model.xml", GradientVariant::MeanGradient, false).unwrap();
    p.validate().unwrap();
}

#[test]
fn malformed_xml_names_file_and_line() {
    let cases: Vec<(String, &str, &str)> = vec![
        (
            GOOD_XML.replace("</Nodes>", "</Nodez>"),
            "model.xml:",
            "malformed XML",
        ),
        (
            GOOD_XML.replace("0.01 0.0 0.0\n", "0.01 abc 0.0\n"),
            "model.xml:5:",
            "not a finite number",
        ),
        (
            GOOD_XML.replace("0 1 2 3 4 5 6 7", "0 1 2 3 4 5 6 9"),
            "model.xml:14:",
            "out of range",
        ),
        (
            GOOD_XML.replace("0 1 2 3 4 5 6 7", "0 1 2 3 4 5 6"),
            "model.xml:13:",
            "not a multiple of 8",
        ),
        (
            GOOD_XML.replace("0 1 2 3 4 5 6 7", "0 3 2 1 4 7 6 5"),
            "model.xml:14:",
            "inverted",
        ),
        (
            GOOD_XML.replace("0 1 2 3 4 5 6 7", "0 1 2 3 4 5 6 6"),
            "model.xml:14:",
            "repeats a node",
        ),
        (
            GOOD_XML.replace("1000.0 10000.0", "-1000.0 10000.0"),
            "model.xml:",
            "moduli must be positive",
        ),
        (
            GOOD_XML.replace("<TimeStep>0.0001</TimeStep>", "<TimeStep>0</TimeStep>"),
            "model.xml:",
            "TimeStep> must be positive",
        ),
        (
            GOOD_XML.replace("<TimeStep>0.0001</TimeStep>", ""),
            "model.xml:",
            "lacks <TimeStep>",
        ),
        (
            GOOD_XML.replace("<Density>1000.0</Density>", ""),
            "model.xml:",
            "no <Density>",
        ),
        (
            GOOD_XML.replace("0 1 2 3\n      </Nodes>", "0 1 2 30\n      </Nodes>"),
            "model.xml:",
            "constraint node 30 out of range",
        ),
        (
            GOOD_XML.replace("Type=\"H8\"", "Type=\"T4\""),
            "model.xml:",
            "not supported",
        ),
        (
            GOOD_XML.replace("NumNodes=\"8\"", "NumNodes=\"9\""),
            "model.xml:",
            "NumNodes",
        ),
        (
            GOOD_XML.replace("DOF=\"all\"", "DOF=\"w\""),
            "model.xml:",
            "expected 0, 1, 2 or all",
        ),
    ];
    for (text, loc, msg) in cases {
        let e = xml_err(&text);
        assert!(
            e.starts_with(loc) && e.contains(msg),
            "expected `{loc}` ... `{msg}`, got: {e}"
        );
    }
}

#[test]
fn node_in_no_element_is_an_error() {
    let text = GOOD_XML
        .replace("NumNodes=\"8\">", "NumNodes=\"9\">")
        .replace(
            "0.0 0.01 0.01\n   </Nodes>",
            "0.0 0.01 0.01\n      0.5 0.5 0.5\n   </Nodes>",
        );
    let e = xml_err(&text);
    assert!(
        e.contains("node 8") && e.contains("belongs to no element"),
        "{e}"
    );
}

/// A small valid scenario, broken one field at a time below (its first line is a comment).
const GOOD_TOML: &str = include_str!("small_block.toml");

fn toml_err(text: &str) -> String {
    match scenario::parse(text, Path::new("case.toml")) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn good_toml_is_accepted() {
    scenario::parse(GOOD_TOML, Path::new("case.toml")).unwrap();
}

#[test]
fn malformed_toml_names_file_and_line_or_field() {
    let cases: Vec<(String, &str)> = vec![
        (
            GOOD_TOML.replace("cells = [2, 2, 2]", "cells = [2, 2, 2"),
            "case.toml:",
        ),
        (
            GOOD_TOML.replace("mu = 800.0", "mu = \"soft\""),
            "case.toml:9:",
        ),
        (
            GOOD_TOML.replace("mu = 800.0", "mu = 800.0\nshear = 1.0"),
            "case.toml:",
        ),
        (GOOD_TOML.replace("density = 1050.0", ""), "case.toml:"),
        (
            GOOD_TOML.replace("mu = 800.0", "mu = -800.0"),
            "field `materials[0] (tissue).mu`",
        ),
        (
            GOOD_TOML.replace("K = 7000.0", "K = 0.0"),
            "field `materials[0] (tissue).K`",
        ),
        (
            GOOD_TOML.replace("density = 1050.0", "density = 0.0"),
            "density",
        ),
        (
            GOOD_TOML.replace("dt = 1e-4", "dt = -1e-4"),
            "field `time.dt`",
        ),
        (
            GOOD_TOML.replace("nodes = \"z_max\"", "nodes = \"top\""),
            "unknown node set `top`",
        ),
        (
            GOOD_TOML.replace("nodes = \"z_max\"", "nodes = [1, 2, 900]"),
            "node 900 out of range",
        ),
        (
            GOOD_TOML.replace("dof = \"z\"", "dof = \"w\""),
            "field `displacement[0].dof`: \"w\" is not a DOF",
        ),
        (
            GOOD_TOML.replace("nodes = \"z_max\"", "nodes = \"z_min\""),
            "already constrained",
        ),
        (
            GOOD_TOML.replace("generator = \"block\"", "generator = \"sphere\""),
            "case.toml:3: unknown variant `sphere`",
        ),
        (
            GOOD_TOML.replace("[mesh]", "[units]\nlength = \"km\"\n\n[mesh]"),
            "case.toml:3: unknown variant `km`",
        ),
        (
            GOOD_TOML.replace("mu = 800.0", "mu = 800.0\nmodel = \"ogden\""),
            "case.toml:10: unknown variant `ogden`",
        ),
        (
            GOOD_TOML.replace(
                "nodes = \"z_min\"",
                "nodes = \"z_min\"\ndofs = [\"x\", \"w\"]",
            ),
            "case.toml:15: dofs: \"w\" is not a DOF",
        ),
        (
            GOOD_TOML.replace("nodes = \"z_min\"", "nodes = \"z_min\"\ndofs = []"),
            "case.toml:15: dofs: expected \"all\" or a list",
        ),
        (
            GOOD_TOML.replace("cells = [2, 2, 2]", "cells = [2, 0, 2]"),
            "field `mesh.cells`",
        ),
    ];
    for (text, want) in cases {
        let e = toml_err(&text);
        assert!(
            e.starts_with("case.toml") && e.contains(want),
            "expected `{want}`, got: {e}"
        );
    }
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = scenario::read(Path::new("/nonexistent/case.toml"))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("/nonexistent/case.toml"), "{e}");
}

/// A time step above the critical one is refused with the limiting element and the
/// largest safe step; forced, the run diverges and stops naming the step, time and element
/// or node, leaving only complete frames behind.
#[test]
fn unstable_time_step_is_refused_and_a_forced_run_stops_cleanly() {
    use sticky_lips::driver::{run, RunOptions};
    use sticky_lips::Precision;
    let s = scenario::parse(
        &GOOD_TOML
            .replace("dt = 1e-4", "dt = 2e-3")
            .replace("total = 0.01", "total = 0.4"),
        Path::new("case.toml"),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("sticky-lips-unstable-{}", std::process::id()));
    let mut opts = RunOptions::new(dir.clone(), Precision::F64, 1);
    let e = run(&s.problem, &opts).expect_err("must refuse").to_string();
    assert!(
        e.contains("exceeds the critical time step") && e.contains("limiting element is"),
        "{e}"
    );
    opts.force_dt = true;
    let e = run(&s.problem, &opts).expect_err("must diverge");
    match &e {
        sticky_lips::Error::Diverged {
            step,
            time,
            element,
            node,
            ..
        } => {
            assert!(
                *step > 0 && *time > 0.0 && (element.is_some() || node.is_some()),
                "{e}"
            );
        }
        other => panic!("expected divergence, got {other}"),
    }
    let msg = e.to_string();
    assert!(
        msg.contains("diverged at step") && msg.contains("t = "),
        "{msg}"
    );
    // every frame listed in the .pvd exists and no temporary file is left
    let pvd = std::fs::read_to_string(dir.join("frames.pvd")).unwrap();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().to_string();
        assert!(!name.contains(".tmp"), "temporary file left: {name}");
        if name.starts_with("frame_") {
            assert!(pvd.contains(&name), "{name} not listed in frames.pvd");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The malformed inputs of the reliability issue that used to crash, run forever or run on
/// nonsense: each is refused, before anything large is allocated, with the file and field.
#[test]
fn oversized_endless_and_non_finite_inputs_are_refused() {
    let mouth = |extra: &str| {
        format!(
            "[mesh]\ngenerator = \"mouth\"\n[mesh.mouth]\n{extra}\n\n[[materials]]\nname = \"t\"\nmu = 800.0\nK = 7000.0\ndensity = 1050.0\n\n[time]\ndt = 1e-5\ntotal = 1e-3\n"
        )
    };
    let cases: Vec<(String, &str)> = vec![
        // a model far larger than any machine's memory, and one that overflows the counts
        (
            GOOD_TOML.replace("cells = [2, 2, 2]", "cells = [1000000000, 1000, 1000]"),
            "field `mesh.cells`: gives 1000000000000000 hexahedra",
        ),
        (
            GOOD_TOML.replace("cells = [2, 2, 2]", "cells = [9223372036854775807, 2, 2]"),
            "fewer than 2^32",
        ),
        (
            GOOD_TOML.replace("cells = [2, 2, 2]", "cells = [1500, 1500, 1500]"),
            "available",
        ),
        (
            mouth("resolution = 55000.0"),
            "field `mesh.mouth.resolution`",
        ),
        (
            mouth("mouth_width = -1.0"),
            "field `mesh.mouth.mouth_width`",
        ),
        // a run that would never end, one that would not start, too many frames
        (
            GOOD_TOML.replace("dt = 1e-4", "dt = 1e-300"),
            "a run may take at most 1000000000",
        ),
        (
            GOOD_TOML.replace("total = 0.01", "total = 1e-5"),
            "the run would take no step",
        ),
        (
            GOOD_TOML.replace("dt = 1e-4", "dt = 1e-8\noutput_every = 1"),
            "a run may write at most 100000",
        ),
        // non-finite numbers (TOML has nan and inf)
        (
            GOOD_TOML.replace("value = 0.001", "value = nan"),
            "field `displacement[0].value`: NaN is not a finite number",
        ),
        (
            GOOD_TOML.replace("size = [0.01, 0.01, 0.01]", "size = [0.01, inf, 0.01]"),
            "field `mesh.size[1]`: inf is not a finite number",
        ),
        // a mesh file that is not there: the scenario and the field are named too
        (
            GOOD_TOML.replace(
                "generator = \"block\"",
                "generator = \"niftysim\"\nfile = \"no-such-model.xml\"",
            ),
            "field `mesh.file`: no-such-model.xml",
        ),
    ];
    for (text, want) in cases {
        let e = toml_err(&text);
        assert!(
            e.starts_with("case.toml") && e.contains(want),
            "expected `{want}`, got: {e}"
        );
    }
}
