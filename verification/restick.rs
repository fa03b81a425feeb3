//! Lips that stick again: `examples/plosive.toml` on the coarse MakeHuman face (resolution
//! 0.25), the jaw keyed open, closed until the lips touch, held closed, and open again ("papa").
//! With paper eq. (11) as written (`rule = "literal"`), a broken saliva element whose stretch
//! across the layer `Q` falls back below the breaking point `Z` gets its unmodified force
//! back: closed lips re-bond. Asserted, from every time step (breaking and re-bonding) and a
//! lip-gap profile every 1 ms (the zip front of each opening, `ZipFront::between`):
//!
//! - each opening breaks every saliva element and parts the lips at the centre first (the
//!   first column to open within 0.2 of the half-width w, as the paper's claim C2);
//! - no element re-bonds while the lips open (the count of broken elements never falls
//!   during either opening), so the literal rule does not make the lips flicker;
//! - every element re-bonds while the jaw closes or holds closed, only where the lips have
//!   come back together (the lip columns of the element closer than the measures' open
//!   threshold, 1 mm) and all of them before the second opening starts;
//! - the face is back at rest when the second opening starts, so the second opening repeats
//!   the first: same first column, and its first opening and 10 -> 90 % times relative to its
//!   start within 2 ms (two samples of the gap profile) of the first's.

use crate::common;
use sticky_lips::io::scenario;
use sticky_lips::measures::{RunMeasures, ZipFront, OPEN_THRESHOLD, ZIP_THRESHOLD};
use sticky_lips::tled::solver::Simulation;

/// Steps between two gap profiles (1 ms at Table 1's dt).
const SAMPLE_EVERY: usize = 100;

struct Event {
    time: f64,
    element: usize,
    /// Largest gap (m) of the lip columns whose nodes belong to the element.
    gap: f64,
}

#[test]
fn lips_stick_again_after_closing() {
    let path = common::repo().join("examples/plosive.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    // the keyed jaw: open, hold, close, hold closed, open, hold
    let doc: toml::Table = toml::from_str(&text).unwrap();
    let keys: Vec<(f64, f64)> = doc["jaw"]["keys"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| {
            let k = k.as_array().unwrap();
            (k[0].as_float().unwrap(), k[1].as_float().unwrap())
        })
        .collect();
    // the same jaw as the paper's run `plosive` (figure `restick`)
    let same: Vec<(f64, f64)> = sticky_lips::paper::PLOSIVE_JAW
        .iter()
        .map(|k| (k[0], k[1]))
        .collect();
    assert_eq!(
        keys, same,
        "examples/plosive.toml and paper::PLOSIVE_JAW differ"
    );
    let angles: Vec<f64> = keys.iter().map(|k| k.1).collect();
    assert!(
        angles[0] == 0.0 && angles[3] == 0.0 && angles[4] == 0.0,
        "{keys:?}"
    );
    assert!(angles[1] > 0.1 && angles[2] == angles[1] && angles[5] == angles[1]);
    let (open1, close_start, closed_at, open2, open2_top) =
        (keys[0].0, keys[2].0, keys[3].0, keys[4].0, keys[5].0);
    // simulated up to the top of the second opening (the example holds a little longer)
    let text = scenario::with_overrides(
        &text,
        "examples/plosive.toml",
        &[("time.total", toml::Value::Float(open2_top))],
    )
    .unwrap();
    let p = scenario::parse(&text, &path).unwrap().problem;
    let cols = p
        .physics
        .lip_columns
        .clone()
        .expect("the face has lip columns");
    let mut sim = Simulation::<f64>::new(&p).unwrap();
    let saliva: Vec<usize> = sim
        .disc
        .saliva
        .elements
        .iter()
        .map(|&e| e as usize)
        .collect();
    let n = saliva.len();
    // the lip columns of each saliva element: those whose upper and lower nodes it holds
    let columns_of: Vec<Vec<usize>> = saliva
        .iter()
        .map(|&e| {
            let conn = p.mesh.elements[e];
            (0..cols.x.len())
                .filter(|&c| conn.contains(&cols.upper[c]) && conn.contains(&cols.lower[c]))
                .collect()
        })
        .collect();
    assert!(columns_of.iter().all(|c| !c.is_empty()), "{columns_of:?}");

    let mut m = RunMeasures::new(cols.clone(), OPEN_THRESHOLD);
    let mut was = vec![false; n];
    let (mut breaks, mut rebonds) = (Vec::<Event>::new(), Vec::<Event>::new());
    // broken count at the end of each phase
    let count_at = |t: f64, sim: &Simulation<f64>| -> Option<usize> {
        ((sim.time() - t).abs() < 0.5 * p.time.dt).then(|| sim.saliva().broken_count())
    };
    let (mut broken_open1, mut broken_closed) = (None, None);
    let mut touch: Option<f64> = None;
    let mut u = sim.displacement_f64();
    m.push(sim.time(), &p.mesh.nodes, &u, 0);
    while !sim.is_finished() {
        sim.step().unwrap();
        let now: Vec<bool> = sim.saliva().broken.clone();
        let changed = now.iter().zip(&was).any(|(a, b)| a != b);
        let closing = touch.is_none() && sim.time() > close_start;
        if changed || closing || sim.step_index() % SAMPLE_EVERY == 0 {
            u = sim.displacement_f64();
        }
        if closing {
            // the lips touch again: the first step of the closing at which a lip column's
            // gap is back at or below zero
            let gap = sticky_lips::measures::lip_gap(&p.mesh.nodes, &u, &cols);
            if gap.iter().any(|g| *g <= 0.0) {
                touch = Some(sim.time());
            }
        }
        if changed {
            let gap = sticky_lips::measures::lip_gap(&p.mesh.nodes, &u, &cols);
            for k in 0..n {
                if now[k] != was[k] {
                    let e = Event {
                        time: sim.time(),
                        element: k,
                        gap: columns_of[k]
                            .iter()
                            .map(|&c| gap[c])
                            .fold(f64::NEG_INFINITY, f64::max),
                    };
                    if now[k] { &mut breaks } else { &mut rebonds }.push(e);
                }
            }
        }
        if sim.step_index() % SAMPLE_EVERY == 0 {
            m.push(sim.time(), &p.mesh.nodes, &u, sim.saliva().broken_count());
        }
        broken_open1 = broken_open1.or(count_at(close_start, &sim));
        broken_closed = broken_closed.or(count_at(open2, &sim));
        was = now;
    }

    // the two openings
    let z1 = ZipFront::between(&m, ZIP_THRESHOLD, open1, close_start);
    let z2 = ZipFront::between(&m, ZIP_THRESHOLD, open2, open2_top);
    for (name, z, t0) in [("first", &z1, open1), ("second", &z2, open2)] {
        let (t, pos) = z
            .first
            .unwrap_or_else(|| panic!("the {name} opening never opens"));
        println!(
            "{name} opening (jaw from {t0} s): first column at |x|/w = {pos:.3}, {:.4} s after \
             the jaw starts; 10 % -> 90 % of the columns open: {:.4} -> {:.4} s ({:.4} s); \
             Spearman {:?}; open at the end {:.2}",
            t - t0,
            z.t10.unwrap() - t0,
            z.t90.unwrap() - t0,
            z.spread().unwrap(),
            z.spearman,
            z.final_open_fraction
        );
    }
    let in_window = |e: &Event, a: f64, b: f64| e.time > a && e.time <= b;
    let first_rebond = rebonds.iter().map(|e| e.time).fold(f64::INFINITY, f64::min);
    let last_rebond = rebonds
        .iter()
        .map(|e| e.time)
        .fold(f64::NEG_INFINITY, f64::max);
    let max_gap = rebonds
        .iter()
        .map(|e| e.gap)
        .fold(f64::NEG_INFINITY, f64::max);
    let rattle: Vec<f64> = breaks
        .iter()
        .filter(|e| in_window(e, close_start, open2))
        .map(|e| e.time)
        .collect();
    println!(
        "while the lips close {} elements break again (from {:?} to {:?} s): they bounce",
        rattle.len(),
        rattle.first(),
        rattle.last()
    );
    println!(
        "{} breaks, {} re-bonds of {n} saliva elements; broken at the end of the first opening \
         {broken_open1:?}, at the start of the second {broken_closed:?}; jaw closed at \
         {closed_at} s, a lip column back at gap <= 0 from {touch:?} s; re-bonds from \
         {first_rebond:.5} to {last_rebond:.5} s, the element's lip gap at its re-bond at most \
         {:.4} mm",
        breaks.len(),
        rebonds.len(),
        max_gap * 1e3
    );

    // each opening breaks every element and opens at the centre first
    assert_eq!(
        broken_open1,
        Some(n),
        "not all saliva broke in the first opening"
    );
    assert_eq!(
        m.frames.last().unwrap().broken,
        n,
        "not all saliva broke in the second opening"
    );
    for (name, z) in [("first", &z1), ("second", &z2)] {
        let pos = z.first.unwrap().1;
        assert!(pos <= 0.2, "the {name} opening starts at |x|/w = {pos}");
    }
    // no re-bond while the lips open
    for (a, b) in [(open1, close_start), (open2, open2_top)] {
        let during: Vec<(f64, usize)> = rebonds
            .iter()
            .filter(|e| in_window(e, a, b))
            .map(|e| (e.time, e.element))
            .collect();
        assert!(during.is_empty(), "re-bonds during an opening: {during:?}");
    }
    // every element re-bonds while closing or closed, only where the lips are together
    assert_eq!(
        broken_closed,
        Some(0),
        "the closed lips did not all re-bond"
    );
    assert!(rebonds.iter().all(|e| in_window(e, close_start, open2)));
    let mut once: Vec<usize> = rebonds.iter().map(|e| e.element).collect();
    once.sort_unstable();
    once.dedup();
    assert_eq!(once.len(), n);
    assert!(
        max_gap < OPEN_THRESHOLD,
        "an element re-bonded with its lips {max_gap} m apart"
    );
    // back at rest when the second opening starts; then the second opening repeats the first
    let rest = m
        .frames
        .iter()
        .rev()
        .find(|f| f.time <= open2 + 1e-9)
        .unwrap();
    let residual = rest.gap.iter().fold(0.0f64, |a, g| a.max(g.abs()));
    assert!(
        residual < 1e-5,
        "lip gap {residual} m when the jaw opens again"
    );
    let (f1, f2) = (z1.first.unwrap(), z2.first.unwrap());
    assert_eq!(f1.1, f2.1, "the openings start at different columns");
    let sample = SAMPLE_EVERY as f64 * p.time.dt;
    for (what, a, b) in [
        ("first column", f1.0 - open1, f2.0 - open2),
        ("10 %", z1.t10.unwrap() - open1, z2.t10.unwrap() - open2),
        ("90 %", z1.t90.unwrap() - open1, z2.t90.unwrap() - open2),
    ] {
        assert!(
            (a - b).abs() <= 2.0 * sample,
            "{what}: {a} s after the first opening's start, {b} s after the second's"
        );
    }
}
