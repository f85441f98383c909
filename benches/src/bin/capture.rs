//! Writes the benches' synthetic capture of a protocol to stdout, for timing the CLI on it
//! (`benches/cli.sh`): `raw` is [`capture`] (every example frame over and over, 1 % noise,
//! seeded), `hex` is [`hex_lines`] (the same frames as hex text, one per line).
//!
//! ```text
//! capture <ub2|sd> <raw|hex> <bytes>
//! ```

use std::io::Write;
use std::process::ExitCode;

use busspec_benches::mixed::{capture, hex_lines, Proto};

const USAGE: &str = "usage: capture <ub2|sd> <raw|hex> <bytes>";

fn run(args: &[String]) -> Result<(), String> {
    let [proto, form, len] = args else {
        return Err(USAGE.to_owned());
    };
    let proto =
        Proto::from_name(proto).ok_or_else(|| format!("unknown protocol `{proto}`\n{USAGE}"))?;
    let len: usize = len
        .parse()
        .map_err(|e| format!("bytes `{len}`: {e}\n{USAGE}"))?;
    let spec = proto.spec();
    let bytes = match form.as_str() {
        "raw" => capture(&spec, len),
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
