//! NiftySim's XML model format (the subset the paper's model used, as NiftySim 2.5 reads it).
//!
//! `<Model>` with `<Nodes DOF="3" NumNodes>`, `<Elements Type="H8" NumEls>`,
//! `<ElementSet Size>` holding a `<Material Type="NH">` (`<ElasticParams>` "mu K", optional
//! `<Density>`) and the element indices, `<Constraint>` of Type `Fix`, `Disp`, `Force` or
//! `Gravity`, and `<SystemParams>`. Constraint semantics are NiftySim's: a `Disp` overrides a
//! `Fix` on the same DOF and several `Disp` values on one DOF add up. Values are SI.
//! Every error names the file and the line.

use crate::boundary::{
    BoundaryConditions, Fixed, Gravity, LoadCurve, LoadShape, NodalForce, PrescribedDisplacement,
};
use crate::element::hex8::GradientVariant;
use crate::error::{Error, Location, Result};
use crate::material::NeoHookean;
use crate::mesh::Mesh;
use crate::problem::{MaterialSpec, Numerics, Problem, TimeSettings};
use roxmltree::{Document, Node};
use std::path::Path;

struct Ctx<'a> {
    file: String,
    doc: &'a Document<'a>,
}

impl Ctx<'_> {
    fn line(&self, n: Node) -> usize {
        self.doc.text_pos_at(n.range().start).row as usize
    }
    fn err(&self, n: Node, msg: impl Into<String>) -> Error {
        Error::input(&self.file, Location::Line(self.line(n)), msg)
    }
    fn err_at(&self, line: usize, msg: impl Into<String>) -> Error {
        Error::input(&self.file, Location::Line(line), msg)
    }

    /// Whitespace-separated tokens of the direct text children of `n`, each with its line.
    fn tokens<'a>(&self, n: Node<'a, '_>) -> Vec<(&'a str, usize)> {
        let mut out = Vec::new();
        for c in n.children().filter(|c| c.is_text()) {
            let line = self.line(c);
            for (k, text_line) in c.text().unwrap_or("").split('\n').enumerate() {
                out.extend(text_line.split_whitespace().map(|t| (t, line + k)));
            }
        }
        out
    }

    fn floats(&self, n: Node, what: &str) -> Result<Vec<f64>> {
        self.tokens(n)
            .into_iter()
            .map(|(t, l)| match t.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(self.err_at(l, format!("{what}: `{t}` is not a finite number"))),
            })
            .collect()
    }

    fn indices(&self, n: Node, what: &str) -> Result<Vec<(u32, usize)>> {
        self.tokens(n)
            .into_iter()
            .map(|(t, l)| match t.parse::<u32>() {
                Ok(v) => Ok((v, l)),
                _ => Err(self.err_at(
                    l,
                    format!("{what}: `{t}` is not a non-negative integer index"),
                )),
            })
            .collect()
    }

    fn attr_usize(&self, n: Node, name: &str) -> Result<Option<usize>> {
        match n.attribute(name) {
            None => Ok(None),
            Some(v) => v.trim().parse::<usize>().map(Some).map_err(|_| {
                self.err(
                    n,
                    format!("attribute {name}=\"{v}\" is not a non-negative integer"),
                )
            }),
        }
    }

    fn child<'b>(&self, n: Node<'b, 'b>, name: &str) -> Option<Node<'b, 'b>> {
        n.children().find(|c| c.has_tag_name(name))
    }

    fn scalar(&self, n: Node, name: &str) -> Result<Option<f64>> {
        match self.child(n, name) {
            None => Ok(None),
            Some(c) => {
                let v = self.floats(c, name)?;
                if v.len() != 1 {
                    return Err(self.err(
                        c,
                        format!("<{name}> must hold one number, found {}", v.len()),
                    ));
                }
                Ok(Some(v[0]))
            }
        }
    }
}

/// Reads a NiftySim XML model. `variant` picks the element gradient variant
/// (`--niftysim-compat` uses `Centroid` and NiftySim's timing).
pub fn read(path: &Path, variant: GradientVariant, niftysim_timing: bool) -> Result<Problem> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse(&text, &path.display().to_string(), variant, niftysim_timing)
}

pub fn parse(
    text: &str,
    file: &str,
    variant: GradientVariant,
    niftysim_timing: bool,
) -> Result<Problem> {
    let doc = Document::parse(text).map_err(|e| {
        let pos = e.pos();
        Error::input(
            file,
            Location::Line(pos.row as usize),
            format!("malformed XML: {e}"),
        )
    })?;
    let cx = Ctx {
        file: file.to_string(),
        doc: &doc,
    };
    let root = doc.root_element();
    if !root.has_tag_name("Model") {
        return Err(cx.err(
            root,
            format!(
                "root element is <{}>, expected <Model>",
                root.tag_name().name()
            ),
        ));
    }
    let nodes = cx.nodes(root)?;
    let (elements, element_lines) = cx.elements(root)?;
    let ne = elements.len();
    let sys = cx.system_params(root)?;
    let (materials, element_material) = cx.materials(root, &sys, &element_lines)?;
    let mut bc = BoundaryConditions::default();
    for c in root.children().filter(|c| c.has_tag_name("Constraint")) {
        cx.constraint(c, nodes.len(), sys.total_time, &mut bc)?;
    }
    let SystemParams {
        dt,
        total_time,
        damping,
        kappa,
        ..
    } = sys;

    let mut mesh = Mesh {
        nodes,
        elements,
        element_lines: Some(element_lines),
        ..Default::default()
    };
    mesh.element_sets
        .insert("all".into(), (0..ne as u32).collect());
    let steps = (total_time / dt).round().max(1.0) as usize;
    let problem = Problem {
        source: file.to_string(),
        mesh,
        materials,
        element_material,
        bc,
        time: TimeSettings {
            dt,
            total_time,
            output_every: (steps / 10).max(1),
        },
        numerics: Numerics {
            damping,
            hourglass_kappa: kappa,
            variant,
            niftysim_timing,
            subcycles: 1,
        },
        additive_constraints: true,
        physics: Default::default(),
    };
    Ok(problem)
}

/// `<SystemParams>`.
struct SystemParams {
    /// `<TimeStep>` (s).
    dt: f64,
    /// `<TotalTime>` (s).
    total_time: f64,
    /// `<DampingCoeff>` (1/s), default 0.
    damping: f64,
    /// `<HGKappa>`, default `Numerics::default()`'s.
    kappa: f64,
    /// `<Density>` (kg/m^3), for materials without their own.
    default_density: Option<f64>,
}

impl Ctx<'_> {
    /// `<Nodes>`: the node coordinates.
    fn nodes(&self, root: Node) -> Result<Vec<[f64; 3]>> {
        let cx = self;
        let nodes_el = cx
            .child(root, "Nodes")
            .ok_or_else(|| cx.err(root, "missing <Nodes>"))?;
        if let Some(dof) = nodes_el.attribute("DOF") {
            if dof.trim() != "3" {
                return Err(cx.err(
                    nodes_el,
                    format!("<Nodes DOF=\"{dof}\">: only 3 DOFs per node are supported"),
                ));
            }
        }
        let coords = cx.floats(nodes_el, "node coordinate")?;
        if coords.len() % 3 != 0 {
            return Err(cx.err(
                nodes_el,
                format!(
                    "<Nodes> holds {} numbers, not a multiple of 3",
                    coords.len()
                ),
            ));
        }
        let nodes: Vec<[f64; 3]> = coords.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        if let Some(nn) = cx.attr_usize(nodes_el, "NumNodes")? {
            if nn != nodes.len() {
                return Err(cx.err(
                    nodes_el,
                    format!("NumNodes=\"{nn}\" but {} nodes are listed", nodes.len()),
                ));
            }
        }

        Ok(nodes)
    }

    /// Every `<Elements>` block: the hexahedra and the line each one starts on.
    fn elements(&self, root: Node) -> Result<(Vec<[u32; 8]>, Vec<usize>)> {
        let cx = self;
        let mut elements = Vec::new();
        let mut element_lines = Vec::new();
        let mut any_elements = false;
        for el in root.children().filter(|c| c.has_tag_name("Elements")) {
            any_elements = true;
            let ty = el.attribute("Type").unwrap_or("");
            if ty != "H8" {
                return Err(cx.err(
                    el,
                    format!("element type \"{ty}\" is not supported (only H8 hexahedra)"),
                ));
            }
            let idx = cx.indices(el, "element node index")?;
            if idx.len() % 8 != 0 {
                return Err(cx.err(
                    el,
                    format!(
                        "<Elements> holds {} indices, not a multiple of 8",
                        idx.len()
                    ),
                ));
            }
            let start = elements.len();
            for c in idx.chunks(8) {
                elements.push(std::array::from_fn(|a| c[a].0));
                element_lines.push(c[0].1);
            }
            if let Some(ne) = cx.attr_usize(el, "NumEls")? {
                if ne != elements.len() - start {
                    return Err(cx.err(
                        el,
                        format!(
                            "NumEls=\"{ne}\" but {} elements are listed",
                            elements.len() - start
                        ),
                    ));
                }
            }
        }
        if !any_elements {
            return Err(cx.err(root, "missing <Elements>"));
        }

        Ok((elements, element_lines))
    }

    /// `<SystemParams>`.
    fn system_params(&self, root: Node) -> Result<SystemParams> {
        let cx = self;
        let sp = cx
            .child(root, "SystemParams")
            .ok_or_else(|| cx.err(root, "missing <SystemParams>"))?;
        let req = |name: &str| -> Result<f64> {
            cx.scalar(sp, name)?
                .ok_or_else(|| cx.err(sp, format!("<SystemParams> lacks <{name}>")))
        };
        let dt = req("TimeStep")?;
        let total_time = req("TotalTime")?;
        let damping = cx.scalar(sp, "DampingCoeff")?.unwrap_or(0.0);
        let kappa = cx
            .scalar(sp, "HGKappa")?
            .unwrap_or(Numerics::default().hourglass_kappa);
        let default_density = cx.scalar(sp, "Density")?;
        for (name, v) in [("TimeStep", dt), ("TotalTime", total_time)] {
            if v <= 0.0 {
                let n = cx.child(sp, name).unwrap();
                return Err(cx.err(n, format!("<{name}> must be positive, got {v}")));
            }
        }

        Ok(SystemParams {
            dt,
            total_time,
            damping,
            kappa,
            default_density,
        })
    }

    /// Every `<ElementSet>` with its `<Material>`: the materials and the material of each
    /// element (every element must have one).
    fn materials(
        &self,
        root: Node,
        sys: &SystemParams,
        element_lines: &[usize],
    ) -> Result<(Vec<MaterialSpec>, Vec<u32>)> {
        let cx = self;
        let ne = element_lines.len();
        let default_density = sys.default_density;
        let mut materials = Vec::new();
        let mut element_material = vec![u32::MAX; ne];
        for (si, set) in root
            .children()
            .filter(|c| c.has_tag_name("ElementSet"))
            .enumerate()
        {
            let mat = cx
                .child(set, "Material")
                .ok_or_else(|| cx.err(set, "<ElementSet> lacks <Material>"))?;
            let ty = mat.attribute("Type").unwrap_or("");
            if ty != "NH" {
                return Err(cx.err(
                    mat,
                    format!("material type \"{ty}\" is not supported (only NH, neo-Hookean)"),
                ));
            }
            let ep = cx
                .child(mat, "ElasticParams")
                .ok_or_else(|| cx.err(mat, "<Material> lacks <ElasticParams>"))?;
            let params = cx.floats(ep, "elastic parameter")?;
            if params.len() != 2 {
                return Err(cx.err(
                    ep,
                    format!(
                        "NH needs 2 elastic parameters (mu K), found {}",
                        params.len()
                    ),
                ));
            }
            let (mu, bulk) = (params[0], params[1]);
            if mu <= 0.0 || bulk <= 0.0 {
                return Err(cx.err(
                    ep,
                    format!("moduli must be positive: mu = {mu}, K = {bulk}"),
                ));
            }
            let density = match cx.scalar(mat, "Density")?.or(default_density) {
                Some(r) if r > 0.0 => r,
                Some(r) => return Err(cx.err(mat, format!("density must be positive, got {r}"))),
                None => return Err(cx.err(mat, "no <Density> in <Material> or <SystemParams>")),
            };
            let mi = materials.len() as u32;
            materials.push(MaterialSpec {
                name: format!("ElementSet{si}"),
                law: NeoHookean { mu, bulk },
                density,
            });
            let mut members = cx.indices(set, "element set member")?;
            let size = cx.attr_usize(set, "Size")?;
            if size == Some(ne) && members.len() < ne {
                // NiftySim's shorthand: a set whose Size is the number of elements holds all of
                // them, whatever indices are listed (its example models list just "0").
                let l = cx.line(set);
                members = (0..ne as u32).map(|e| (e, l)).collect();
            }
            if let Some(sz) = size {
                if sz != members.len() {
                    return Err(cx.err(
                        set,
                        format!("Size=\"{sz}\" but {} elements are listed", members.len()),
                    ));
                }
            }
            for (e, l) in members {
                if e as usize >= ne {
                    return Err(cx.err_at(
                        l,
                        format!(
                            "element set member {e} out of range (the model has {ne} elements)"
                        ),
                    ));
                }
                element_material[e as usize] = mi;
            }
        }
        if materials.is_empty() {
            return Err(cx.err(root, "no <ElementSet>: elements have no material"));
        }
        if let Some(e) = element_material.iter().position(|&m| m == u32::MAX) {
            return Err(cx.err_at(
                element_lines[e],
                format!("element {e} is in no <ElementSet>"),
            ));
        }

        Ok((materials, element_material))
    }

    /// One `<Constraint>` (Fix, Disp, Force, Gravity) into `bc`; its load curve spans the
    /// whole run.
    fn constraint(
        &self,
        c: Node,
        nn: usize,
        total_time: f64,
        bc: &mut BoundaryConditions,
    ) -> Result<()> {
        let cx = self;
        let whole_run = |shape| LoadCurve {
            shape,
            start: 0.0,
            duration: total_time,
        };
        let ty = c.attribute("Type").unwrap_or("");
        let nodes_el = cx
            .child(c, "Nodes")
            .ok_or_else(|| cx.err(c, "<Constraint> lacks <Nodes>"))?;
        let mut cnodes = Vec::new();
        for (n, l) in cx.indices(nodes_el, "constraint node")? {
            if n as usize >= nn {
                return Err(cx.err_at(
                    l,
                    format!("constraint node {n} out of range (the model has {nn} nodes)"),
                ));
            }
            cnodes.push(n);
        }
        if let Some(k) = cx.attr_usize(c, "NumNodes")? {
            if k != cnodes.len() {
                return Err(cx.err(
                    c,
                    format!("NumNodes=\"{k}\" but {} nodes are listed", cnodes.len()),
                ));
            }
        }
        match ty {
            "Fix" => {
                let mut mask = [false; 3];
                for d in cx.constraint_dofs(c)? {
                    mask[d] = true;
                }
                bc.fixed.push(Fixed {
                    nodes: cnodes,
                    dofs: mask,
                });
            }
            "Disp" | "Force" => {
                let curve = whole_run(cx.load_shape(c)?);
                let values = cx.magnitudes(c, cnodes.len())?;
                for d in cx.constraint_dofs(c)? {
                    if ty == "Disp" {
                        bc.displacements.push(PrescribedDisplacement {
                            nodes: cnodes.clone(),
                            dof: d,
                            values: values.clone(),
                            curve: curve.clone(),
                        });
                    } else {
                        bc.forces.push(NodalForce {
                            nodes: cnodes.clone(),
                            dof: d,
                            values: values.clone(),
                            curve: curve.clone(),
                        });
                    }
                }
            }
            "Gravity" => bc
                .gravity
                .push(cx.gravity(c, cnodes, whole_run(cx.load_shape(c)?))?),
            other => {
                return Err(cx.err(
                    c,
                    format!(
                        "constraint type \"{other}\" is not supported (Fix, Disp, Force, Gravity)"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// A constraint's `DOF` attribute: `0`, `1`, `2` or `all`.
    fn constraint_dofs(&self, c: Node) -> Result<Vec<usize>> {
        let cx = self;
        match c.attribute("DOF").map(str::trim) {
            Some("0") => Ok(vec![0]),
            Some("1") => Ok(vec![1]),
            Some("2") => Ok(vec![2]),
            Some("all") => Ok(vec![0, 1, 2]),
            Some(o) => Err(cx.err(c, format!("DOF=\"{o}\": expected 0, 1, 2 or all"))),
            None => Err(cx.err(c, "<Constraint> lacks the DOF attribute")),
        }
    }

    /// A constraint's `LoadShape` attribute.
    fn load_shape(&self, c: Node) -> Result<LoadShape> {
        let cx = self;
        let s = c
            .attribute("LoadShape")
            .ok_or_else(|| cx.err(c, "<Constraint> lacks LoadShape"))?;
        LoadShape::parse(s).ok_or_else(|| {
            cx.err(
                c,
                format!("LoadShape=\"{s}\": expected RAMP, POLY345, STEP, HILLY or RAMPHOLD"),
            )
        })
    }

    /// A constraint's `<Magnitudes>`: `count` values, UNIFORM (one for all) or DIFFORM.
    fn magnitudes(&self, c: Node, count: usize) -> Result<Vec<f64>> {
        let cx = self;
        let m = cx
            .child(c, "Magnitudes")
            .ok_or_else(|| cx.err(c, "<Constraint> lacks <Magnitudes>"))?;
        let v = cx.floats(m, "magnitude")?;
        match m.attribute("Type") {
            Some("UNIFORM") => {
                if v.len() != 1 {
                    return Err(cx.err(
                        m,
                        format!("UNIFORM magnitudes need 1 value, found {}", v.len()),
                    ));
                }
                Ok(vec![v[0]; count])
            }
            Some("DIFFORM") => {
                if v.len() != count {
                    return Err(cx.err(
                        m,
                        format!(
                            "DIFFORM magnitudes need one value per node ({}), found {}",
                            count,
                            v.len()
                        ),
                    ));
                }
                Ok(v)
            }
            other => Err(cx.err(
                m,
                format!("Magnitudes Type={other:?}: expected UNIFORM or DIFFORM"),
            )),
        }
    }

    /// A Gravity constraint on `nodes`: magnitude times the unit direction.
    fn gravity(&self, c: Node, nodes: Vec<u32>, curve: LoadCurve) -> Result<Gravity> {
        let cx = self;
        let cnodes = nodes;
        let mag = cx
            .scalar(c, "AccelerationMagnitude")?
            .ok_or_else(|| cx.err(c, "Gravity constraint lacks <AccelerationMagnitude>"))?;
        let dir_el = cx
            .child(c, "AccelerationDirection")
            .ok_or_else(|| cx.err(c, "Gravity constraint lacks <AccelerationDirection>"))?;
        let dir = cx.floats(dir_el, "acceleration direction")?;
        if dir.len() != 3 {
            return Err(cx.err(dir_el, "<AccelerationDirection> needs 3 numbers"));
        }
        let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        if n == 0.0 {
            return Err(cx.err(dir_el, "<AccelerationDirection> is the zero vector"));
        }
        Ok(Gravity {
            nodes: Some(cnodes),
            acceleration: [mag * dir[0] / n, mag * dir[1] / n, mag * dir[2] / n],
            curve,
        })
    }
}

/// One element set of a model written by [`write_model`]: its elements and neo-Hookean
/// material.
pub struct SetMaterial<'a> {
    pub elements: &'a [u32],
    pub mu: f64,
    pub bulk: f64,
    pub density: f64,
}

/// Writes a mesh as a NiftySim XML model (nodes, H8 elements, one `<ElementSet>` per
/// material set, `<SystemParams>`), atomically: the format the paper's pipeline produced
/// from its extruded OBJ. Constraints are left to the scenario that uses it.
pub fn write_model(
    path: &Path,
    mesh: &Mesh,
    sets: &[SetMaterial],
    dt: f64,
    total_time: f64,
    damping: f64,
    kappa: f64,
) -> Result<()> {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<Model>");
    let _ = writeln!(s, "   <Nodes DOF=\"3\" NumNodes=\"{}\">", mesh.nodes.len());
    for x in &mesh.nodes {
        let _ = writeln!(s, "      {:?} {:?} {:?}", x[0], x[1], x[2]);
    }
    let _ = writeln!(
        s,
        "   </Nodes>\n   <Elements NumEls=\"{}\" Type=\"H8\">",
        mesh.elements.len()
    );
    for c in &mesh.elements {
        let _ = writeln!(
            s,
            "      {} {} {} {} {} {} {} {}",
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]
        );
    }
    let _ = writeln!(s, "   </Elements>");
    for set in sets {
        let _ = writeln!(s, "   <ElementSet Size=\"{}\">", set.elements.len());
        let _ = writeln!(
            s,
            "      <Material Type=\"NH\">\n         <ElasticParams NumParams=\"2\">\n            {:?} {:?}\n         </ElasticParams>\n         <Density>{:?}</Density>\n      </Material>",
            set.mu, set.bulk, set.density
        );
        for chunk in set.elements.chunks(16) {
            let line: Vec<String> = chunk.iter().map(|e| e.to_string()).collect();
            let _ = writeln!(s, "      {}", line.join(" "));
        }
        let _ = writeln!(s, "   </ElementSet>");
    }
    let _ = writeln!(
        s,
        "   <SystemParams>\n      <TimeStep>{dt:?}</TimeStep>\n      <TotalTime>{total_time:?}</TotalTime>\n      <DampingCoeff>{damping:?}</DampingCoeff>\n      <HGKappa>{kappa:?}</HGKappa>\n   </SystemParams>\n</Model>"
    );
    crate::io::atomic::write_atomic(path, s.as_bytes()).map_err(|e| Error::io(path, e))
}
