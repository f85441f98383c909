//! Generates the UB2, SD, Modbus RTU and Dynamixel 1.0 modules from the repository's specs
//! (`spec/` in this package is the repository's `spec/` directory, so the package carries the
//! specs it is built from).

fn main() {
    busspec_codegen::Builder::new()
        .specs([
            "spec/sd.yaml",
            "spec/ub2.yaml",
            "spec/modbus.yaml",
            "spec/dynamixel.yaml",
        ])
        .compile();
}
