//! Generates the UB2, SD, Modbus RTU, Dynamixel 1.0, Pelco D, Pelco P, CRSF and Dynamixel 2.0 modules from the
//! repository's specs (`spec/` in this package is the repository's `spec/` directory, so the
//! package carries the specs it is built from): each behind the cargo feature of its name (`ub2`,
//! `sd`, `modbus`, `dynamixel`, `pelco_d`, `pelco_p`, `crsf`, `dynamixel2`; all eight by default), so a firmware build
//! compiles only the protocols it names.
//! With none of them on, the crate has no protocol module and `PROTOCOLS` is empty.

/// Each protocol's feature and spec, in the order the modules are generated.
const PROTOCOLS: [(&str, &str); 8] = [
    ("sd", "spec/sd.yaml"),
    ("ub2", "spec/ub2.yaml"),
    ("modbus", "spec/modbus.yaml"),
    ("dynamixel", "spec/dynamixel.yaml"),
    ("pelco_d", "spec/pelco_d.yaml"),
    ("pelco_p", "spec/pelco_p.yaml"),
    ("crsf", "spec/crsf.yaml"),
    ("dynamixel2", "spec/dynamixel2.yaml"),
];

fn main() {
    let specs: Vec<&str> = PROTOCOLS
        .iter()
        .filter(|(feature, _)| {
            std::env::var_os(format!("CARGO_FEATURE_{}", feature.to_uppercase())).is_some()
        })
        .map(|&(_, spec)| spec)
        .collect();
    if !specs.is_empty() {
        busspec_codegen::Builder::new().specs(specs).compile();
        return;
    }
    // No protocol named: the index alone (no module, no names), which the Builder, made for
    // at least one spec, does not write.
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let index = busspec_codegen::emit_index(&[]).unwrap_or_else(|e| panic!("{e}"));
    let path = out.join(busspec_codegen::INDEX_FILE);
    if let Err(e) = busspec_codegen::write_if_changed(&path, &index) {
        panic!("{}: cannot write: {e}", path.display());
    }
}
