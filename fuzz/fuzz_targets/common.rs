// Shared by the fuzz targets.

/// A small memory limit for the models an input may describe (the budget check refuses larger
/// ones, as it refuses what does not fit the machine), then the input as text, if it is UTF-8.
pub fn text(data: &[u8]) -> Option<&str> {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| std::env::set_var(sticky_lips::mesh::budget::LIMIT_VARIABLE, "256"));
    std::str::from_utf8(data).ok()
}

/// A valid problem of at most 500 nodes is built and stepped twice (errors are fine).
#[allow(dead_code)]
pub fn step_small(p: &sticky_lips::problem::Problem) {
    if p.validate().is_err() || p.mesh.nodes.len() > 500 {
        return;
    }
    if let Ok(mut sim) = sticky_lips::tled::Simulation::<f64>::new(p) {
        for _ in 0..2.min(sim.num_steps()) {
            if sim.step().is_err() {
                break;
            }
        }
    }
}
