//! The build-script API: what `Builder::generate` writes, and the errors it gives instead of
//! panicking — every broken spec reported together, with its path; duplicate protocols; no
//! specs; no output directory.

use std::path::{Path, PathBuf};

use busspec_codegen::{Builder, Error, INDEX_FILE};

fn fixture(dir: &str, name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures")
        .join(dir)
        .join(name)
}

fn out_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("busspec-builder-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn writes_one_module_per_spec_and_the_index_and_rewrites_nothing_unchanged() {
    let out = out_dir("ok");
    let builder = Builder::new()
        .spec(fixture("valid", "minimal.yaml"))
        .spec(fixture("valid", "minimal_crc.yaml"))
        .out_dir(&out);
    let g = builder.generate().unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(g.protocols, ["mini", "mini_crc"]);
    assert_eq!(g.files.len(), 3);
    assert_eq!(g.files[2], out.join(INDEX_FILE));
    let index = std::fs::read_to_string(out.join(INDEX_FILE)).unwrap();
    assert!(
        index.contains("pub const PROTOCOLS: &[&str] = &[\"mini\", \"mini_crc\"];"),
        "{index}"
    );
    assert!(
        index.contains(
            "\"mini_crc\" => ::core::option::Option::Some(visitor.visit::<mini_crc::MiniCrc>())"
        ),
        "{index}"
    );
    // A second run with nothing changed leaves every file as it was, to the modification time.
    let times = |files: &[PathBuf]| -> Vec<_> {
        files
            .iter()
            .map(|f| std::fs::metadata(f).unwrap().modified().unwrap())
            .collect()
    };
    let before = times(&g.files);
    std::thread::sleep(std::time::Duration::from_millis(20));
    let again = builder.generate().unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(times(&again.files), before);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn every_broken_spec_is_reported_with_its_file_and_path_and_nothing_is_written() {
    let out = out_dir("broken");
    let errors = Builder::new()
        .spec(fixture("broken", "undefined_unit.yaml"))
        .spec(fixture("valid", "minimal.yaml"))
        .spec(fixture("broken", "bits_overlap.yaml"))
        .out_dir(&out)
        .generate()
        .expect_err("two broken specs");
    assert_eq!(errors.len(), 2, "{errors:?}");
    let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
    assert!(matches!(errors[0], Error::Spec(_)));
    assert!(text[0].contains("undefined_unit.yaml: "), "{}", text[0]);
    assert!(text[0].contains("is not defined in `units`"), "{}", text[0]);
    assert!(text[1].contains("bits_overlap.yaml: "), "{}", text[1]);
    assert!(!out.exists(), "nothing is written when a spec is broken");
}

#[test]
fn a_missing_spec_file_two_specs_of_one_protocol_and_no_specs_are_errors() {
    let out = out_dir("misc");
    let missing = Builder::new()
        .spec("no/such/spec.yaml")
        .out_dir(&out)
        .generate()
        .expect_err("missing file");
    assert!(
        missing[0].to_string().starts_with("no/such/spec.yaml: "),
        "{}",
        missing[0]
    );

    let twice = Builder::new()
        .spec(fixture("valid", "minimal.yaml"))
        .spec(fixture("valid", "minimal.yaml"))
        .out_dir(&out)
        .generate()
        .expect_err("the same protocol twice");
    assert!(
        matches!(&twice[0], Error::DuplicateProtocol { name, .. } if name == "mini"),
        "{twice:?}"
    );

    let none = Builder::new()
        .out_dir(&out)
        .generate()
        .expect_err("no specs");
    assert!(matches!(none[0], Error::NoSpecs));
    assert!(!out.exists());
}

/// A spec that includes a file of common types: the module embeds the spec with them in place
/// (`NAME.spec.yaml`, written beside the modules, loads on its own), and `inputs` names the
/// included file so that a build script reruns when it changes.
#[test]
fn a_spec_with_includes_embeds_one_text_and_names_every_file_read() {
    let out = out_dir("include");
    let dir = out.join("spec");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(fixture("valid", "minimal.yaml")).unwrap();
    let (a, b) = (text.find("units:").unwrap(), text.find("enums:").unwrap());
    std::fs::write(dir.join("common.yaml"), &text[a..b]).unwrap();
    let spec = dir.join("mini.yaml");
    std::fs::write(
        &spec,
        format!("include: common.yaml\n{}{}", &text[..a], &text[b..]),
    )
    .unwrap();
    let g = Builder::new()
        .spec(&spec)
        .out_dir(out.join("gen"))
        .generate()
        .unwrap_or_else(|e| panic!("{e:?}"));
    let flat_path = out.join("gen/mini.spec.yaml");
    assert_eq!(g.files[0], flat_path);
    assert_eq!(
        g.inputs,
        [
            spec.clone(),
            std::fs::canonicalize(dir.join("common.yaml")).unwrap()
        ]
    );
    let flat = std::fs::read_to_string(&flat_path).unwrap();
    let p = busspec_model::load_str("mini.spec.yaml", &flat).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(p.units.len(), 4);
    let module = std::fs::read_to_string(out.join("gen/mini.rs")).unwrap();
    let embeds = format!(
        "{:?}",
        std::path::absolute(&flat_path).unwrap().to_string_lossy()
    );
    let at = module
        .find("SPEC_YAML: &str = include_str!(")
        .expect("SPEC_YAML");
    assert!(
        module[at..]
            .trim_start_matches(|c: char| c != '"')
            .starts_with(&embeds),
        "SPEC_YAML does not embed {embeds}"
    );
    // A broken included file is the spec's error, located in that file.
    std::fs::write(
        dir.join("common.yaml"),
        text[a..b].replace("scale: \"0.01\"", "scale: \"0\""),
    )
    .unwrap();
    let e = Builder::new()
        .spec(&spec)
        .out_dir(out.join("gen"))
        .generate()
        .expect_err("scale 0");
    assert!(
        e[0].to_string()
            .ends_with("mini.yaml: include common.yaml: units.capacitance.scale: scale 0 must be greater than zero"),
        "{}",
        e[0]
    );
    let _ = std::fs::remove_dir_all(&out);
}
