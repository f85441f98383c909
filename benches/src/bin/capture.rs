//! Writes the benches' synthetic capture of a protocol to stdout, for timing the CLI on it
//! (`benches/cli.sh`): `raw` is [`capture`](busspec_benches::mixed::capture) (every example
//! frame over and over, 1 % noise, seeded), `hex` is [`hex_lines`] (the same frames as hex
//! text, one per line). The protocol is
//! a built-in one's name or a spec file (`spec/modbus.yaml`), whose examples make the capture.
//!
//! ```text
//! capture <ub2|sd|SPEC.yaml> <raw|hex> <bytes> [noise per mille, default 10]
//! ```

use std::io::Write;
use std::process::ExitCode;

use busspec_benches::mixed::{capture_with_noise, hex_lines, Proto, NOISE_PER_MILLE};

const USAGE: &str = "usage: capture <ub2|sd|SPEC.yaml> <raw|hex> <bytes> [noise per mille]";

fn run(args: &[String]) -> Result<(), String> {
    let (proto, form, len, noise) = match args {
        [proto, form, len] => (proto, form, len, None),
        [proto, form, len, noise] => (proto, form, len, Some(noise)),
        _ => return Err(USAGE.to_owned()),
    };
    let per_mille = match noise {
        None => NOISE_PER_MILLE,
        Some(n) => n
            .parse()
            .ok()
            .filter(|&n| n < 1000)
            .ok_or_else(|| format!("noise `{n}`: per mille, 0 to 999\n{USAGE}"))?,
    };
    let len: usize = len
        .parse()
        .map_err(|e| format!("bytes `{len}`: {e}\n{USAGE}"))?;
    let spec = match Proto::from_name(proto) {
        Some(proto) => proto.spec(),
        None if proto.ends_with(".yaml") => {
            busspec_model::load_file(std::path::Path::new(proto)).map_err(|e| e.to_string())?
        }
        None => return Err(format!("unknown protocol `{proto}`\n{USAGE}")),
    };
    let bytes = match form.as_str() {
        "raw" => capture_with_noise(&spec, len, per_mille),
        "hex" => hex_lines(&spec, len).into_bytes(),
        other => return Err(format!("unknown form `{other}`\n{USAGE}")),
    };
    std::io::stdout()
        .lock()
        .write_all(&bytes)
        .map_err(|e| format!("cannot write stdout: {e}"))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
