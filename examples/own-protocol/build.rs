//! Generates the `thermo` module from the spec: `OUT_DIR/thermo.rs` and `OUT_DIR/protocols.rs`.
//! A spec error fails the build with one line per error, `file: path: message`.

fn main() {
    busspec_codegen::Builder::new()
        .spec("spec/thermo.yaml")
        .compile();
}
