//! Generates the UB2 and SD modules of the benches' subset of messages (the ones the
//! hand-written codec implements): the specs with every other message left out, through the
//! same generator as `busspec-protocols`.

use std::path::Path;

use busspec_model::ir::Protocol;

include!("../src/subset.rs");

/// `p` with only the messages named in `keep`; the indices between commands and responses
/// are renumbered.
fn subset(mut p: Protocol, keep: &[&str]) -> Protocol {
    let kept = |names: Vec<&str>| -> Vec<Option<usize>> {
        let mut next = 0;
        names
            .into_iter()
            .map(|n| {
                keep.contains(&n).then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect()
    };
    let commands = kept(p.commands.iter().map(|m| m.name.as_str()).collect());
    let responses = kept(p.responses.iter().map(|m| m.name.as_str()).collect());
    p.commands.retain(|m| keep.contains(&m.name.as_str()));
    p.responses.retain(|m| keep.contains(&m.name.as_str()));
    for c in &mut p.commands {
        c.responses = c
            .responses
            .iter()
            .filter_map(|(r, why)| responses[*r].map(|r| (r, why.clone())))
            .collect();
    }
    for r in &mut p.responses {
        r.answers = r.answers.iter().filter_map(|c| commands[*c]).collect();
    }
    p.common_responses = p
        .common_responses
        .iter()
        .filter_map(|r| responses[*r])
        .collect();
    p.examples.clear();
    p
}

fn main() {
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let mut code = String::new();
    for (file, keep) in [("ub2.yaml", UB2_SUBSET), ("sd.yaml", SD_SUBSET)] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../spec")
            .join(file);
        println!("cargo::rerun-if-changed={}", path.display());
        let p = busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"));
        let p = subset(p, keep);
        let spec = path.display().to_string();
        code.push_str(
            &busspec_codegen::emit::emit_module(&p, &spec, &spec).unwrap_or_else(|e| panic!("{e}")),
        );
    }
    std::fs::write(Path::new(&out).join("subset.rs"), code).expect("OUT_DIR is writable");
    println!("cargo::rerun-if-changed=../src/subset.rs");
}
