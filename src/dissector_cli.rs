//! `busspec dissector`: the Wireshark Lua dissector of built-in protocols and spec files
//! (`busspec_model::dissector` renders it).

use std::io::Write;
use std::path::PathBuf;

use busspec_model::{dissector, load_file, Protocol};
use clap::Args;

use crate::frames::Engine;

pub const DISSECTOR_HELP: &str = "\
Write a Wireshark Lua dissector for protocols: built-in ones by name (default: all eight, ub2,
sd, modbus, dynamixel, pelco_d, pelco_p, crsf and dynamixel2, when no protocol and no --spec is given) and the specs of --spec
files, all in one Lua file (stdout, or -o FILE).

Load it with `wireshark -X lua_script:FILE` or `tshark -X lua_script:FILE -r CAPTURE`, or copy
it into Wireshark's personal Lua plugins folder (Help > About Wireshark > Folders) to have it
always. It shows the pcapng captures busspec writes (`decode --stream P CAPTURE --pcapng OUT`,
`talk --pcapng OUT`): it registers on link type USER0 (147) and, where the file holds several
protocols, picks each packet's by its interface description (`busspec NAME`).

For each packet it shows, generated from the spec: the message by its spec name, its
direction (from the packet's direction flags), address and code; every field by its spec
name with its value exactly as `busspec decode` prints it (the physical value in the spec's
unit, enum and special values and flags by name, text, lists) and its raw value, filterable as
busspec_NAME.field.MESSAGE.FIELD (and .raw); the checksum verified (busspec_NAME.checksum.status
Good or Bad, an expert error with busspec's `checksum mismatch` text when wrong); every rule of
the spec the frame breaks (a range, the address rules, the broadcast rule) as an expert
warning in busspec's words; a response paired with the request before it (\"Response to
frame N\" and the time since it; the request's \"Response in frame N\" where Wireshark makes
two passes, `tshark -2`); the spec's document and the message's section; bytes that start no
frame, and frames only their request could tell apart, as such.

Exit status 0; 2 for a protocol that is not built in, a spec that does not load or a
protocol named twice; 1 when the file cannot be written.";

#[derive(Args)]
pub struct DissectorArgs {
    /// Built-in protocols: ub2, sd, modbus, dynamixel, pelco_d, pelco_p, crsf, dynamixel2 (default: all eight, unless --spec is
    /// given). A name a --spec file defines takes that spec.
    protocols: Vec<String>,
    /// Also a protocol from this spec file (repeat for several).
    #[arg(long, value_name = "FILE")]
    spec: Vec<PathBuf>,
    /// Write the dissector to FILE instead of stdout.
    #[arg(short, long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub fn run(args: DissectorArgs) -> Result<(), String> {
    let refuse = |msg: String| super::usage_error("dissector", msg);
    let mut chosen: Vec<Protocol> = Vec::new();
    for file in &args.spec {
        match load_file(file) {
            Ok(p) => chosen.push(p),
            Err(d) => {
                eprintln!("{}", super::load_errors(&d));
                std::process::exit(2);
            }
        }
    }
    let mut names = args.protocols.clone();
    if names.is_empty() && args.spec.is_empty() {
        names = busspec_protocols::PROTOCOLS
            .iter()
            .map(|s| s.to_string())
            .collect();
    }
    for name in &names {
        if chosen.iter().any(|p| &p.name == name) {
            if args.protocols.iter().filter(|n| *n == name).count() > 1 {
                refuse(format!("protocol `{name}` is named twice"));
            }
            continue;
        }
        match Engine::built_in(name) {
            Some(engine) => chosen.push(engine?.spec),
            None => refuse(format!(
                "unknown protocol `{name}`: the built-in ones are {} (or give --spec FILE)",
                busspec_protocols::PROTOCOLS.join(", ")
            )),
        }
    }
    for (i, p) in chosen.iter().enumerate() {
        if chosen[..i].iter().any(|q| q.name == p.name) {
            refuse(format!(
                "protocol `{}` is given twice: one dissector file shows each protocol once",
                p.name
            ));
        }
    }
    let refs: Vec<&Protocol> = chosen.iter().collect();
    let lua = dissector::render(&refs);
    match &args.out {
        Some(path) => std::fs::write(path, lua)
            .map_err(|e| format!("error: cannot write {}: {e}", path.display())),
        None => {
            let mut out = std::io::stdout().lock();
            match out.write_all(lua.as_bytes()).and_then(|()| out.flush()) {
                Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                    Err(format!("error: cannot write the dissector: {e}"))
                }
                _ => Ok(()),
            }
        }
    }
}
