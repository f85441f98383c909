//! Writes the seed corpus and the dictionaries under `fuzz/` from the specs' examples:
//! `cargo run -p busspec-fuzz-bodies --bin make-corpus`.

fn main() {
    let fuzz = busspec_fuzz_bodies::seeds::repo_root().join("fuzz");
    if let Err(e) = busspec_fuzz_bodies::seeds::write(&fuzz) {
        eprintln!("error: cannot write under {}: {e}", fuzz.display());
        std::process::exit(1);
    }
    println!(
        "wrote the seed corpus and dictionaries under {}",
        fuzz.display()
    );
}
