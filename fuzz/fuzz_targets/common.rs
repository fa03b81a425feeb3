// Shared by the fuzz targets: a small memory limit for the models an input may describe (the
// budget check refuses larger ones, as it refuses what does not fit the machine).
pub fn init() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| std::env::set_var(sticky_lips::mesh::budget::LIMIT_VARIABLE, "256"));
}
