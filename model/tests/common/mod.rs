//! What more than one of the model's test files uses.

/// A small xorshift generator: the tests need no dependency for their random frames, and a
/// failure replays from its seed.
#[allow(dead_code)]
pub struct Rng(pub u64);

#[allow(dead_code)]
impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Valid fixture `name` (`tests/fixtures/valid/NAME.yaml`) as it is, and with each `(from, to)`
/// edit made (each `from` must occur) and its examples and errata dropped (an edit that
/// changes frames would fail them): the two revisions a diff test compares.
#[allow(dead_code)]
pub fn revisions(
    name: &str,
    edits: &[(&str, &str)],
) -> (busspec_model::Protocol, busspec_model::Protocol) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/valid")
        .join(format!("{name}.yaml"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let old =
        busspec_model::load_str(&format!("{name}.yaml"), &text).unwrap_or_else(|d| panic!("{d}"));
    let mut changed = text;
    for (from, to) in edits {
        assert!(changed.contains(from), "{name}.yaml holds no `{from}`");
        changed = changed.replace(from, to);
    }
    // Top-level `examples:` and `errata:` blocks out, whatever follows them.
    let mut kept = String::new();
    let mut dropping = false;
    for line in changed.lines() {
        let top = !line.starts_with([' ', '#', '-']) && !line.is_empty();
        if top {
            dropping = line.starts_with("examples:") || line.starts_with("errata:");
        }
        if !dropping {
            kept.push_str(line);
            kept.push('\n');
        }
    }
    kept.push_str("examples: []\nerrata: []\n");
    let new = busspec_model::load_str("changed.yaml", &kept).unwrap_or_else(|d| panic!("{d}"));
    (old, new)
}
