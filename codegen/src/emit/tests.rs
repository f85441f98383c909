use super::*;

fn field(range: (i64, i64), special: &[i64]) -> Field {
    Field {
        name: "t".into(),
        doc: String::new(),
        ty: FieldType::U8,
        offset: 0,
        width: 1,
        signed: false,
        byte_order: ByteOrder::Little,
        word_swapped: false,
        bcd: false,
        unit: None,
        range: Some(range),
        constant: None,
        enumeration: None,
        flags: None,
        equals: None,
        special: special
            .iter()
            .map(|&value| Special {
                value,
                name: format!("s{value}"),
                doc: String::new(),
            })
            .collect(),
        bits: Vec::new(),
        repeat: None,
        packed: None,
        follows: None,
        record: Vec::new(),
        bytes_from: None,
        present: None,
        header: false,
        part: 0,
    }
}

#[test]
fn a_range_check_that_cannot_fail_is_left_out() {
    let u8_limits = (0, 255);
    // SD's temperatures: 1..=254, with 0 and 255 special, is every byte.
    assert!(leaf_range(&field((1, 254), &[0, 255]), None, u8_limits).is_none());
    assert!(leaf_range(&field((0, 255), &[]), None, u8_limits).is_none());
    // A wider typed value is checked, as is a byte that no value admits.
    assert!(leaf_range(&field((0, 255), &[]), None, (0, 65535)).is_some());
    let range = leaf_range(&field((1, 254), &[0]), None, u8_limits).unwrap();
    assert_eq!(
        range.to_string(),
        quote!(.range(1, 254).or(&[0])).to_string()
    );
    let range = leaf_range(&field((1, 100), &[0, 50]), None, u8_limits).unwrap();
    assert_eq!(
        range.to_string(),
        quote!(.range(1, 100).or(&[0])).to_string()
    );
    let range = leaf_range(&field((1, 100), &[50]), None, u8_limits).unwrap();
    assert_eq!(range.to_string(), quote!(.range(1, 100)).to_string());
}

/// The block-marking `head_cells` gives every cell what the mask of every shape whose code
/// is a prefix of the cell's bytes gives, for codes of zero, one and two bytes.
#[test]
fn head_cells_agree_with_each_cells_shapes() {
    let lengths = [12, 9, 7, 5];
    let shapes: Vec<(&[u8], u128)> = vec![
        (&[0x01, 0x02], 1),
        (&[0x01, 0x02], 1 << 64),
        (&[0x01, 0x7F], 1 << 1),
        (&[0x01], 1 << 2),
        (&[0xFF, 0x00], 1 << 65),
        (&[0xFF, 0xFF], 1 << 3 | 1 << 2),
        (&[], 1 << 67),
    ];
    let cells = head_cells(&shapes, 2, &lengths);
    assert_eq!(cells.len(), 65536);
    for (i, &got) in cells.iter().enumerate() {
        let code = [(i >> 8) as u8, i as u8];
        let mask = shapes
            .iter()
            .filter(|s| s.0.iter().zip(&code).all(|(a, b)| a == b))
            .fold(0u128, |a, s| a | s.1);
        assert_eq!(got, candidate_cell(mask, &lengths), "cell {code:02X?}");
    }
    let one: Vec<(&[u8], u128)> = vec![(&[0x10], 1), (&[0x20], 1 << 1 | 1 << 64), (&[], 1 << 66)];
    let cells = head_cells(&one, 1, &lengths);
    assert_eq!(cells.len(), 256);
    assert_eq!(cells[0x10], candidate_cell(1 | 1 << 66, &lengths));
    assert_eq!(cells[0x20], 0xFFFF);
    assert_eq!(cells[0x30], candidate_cell(1 << 66, &lengths));
    assert_ne!(cells[0x10], cells[0x30]);
}

/// A doc line written as `doc_lit` writes it prints as the escaped string does, whatever
/// the text holds: quotes, a quote and hashes, backslashes, non-ASCII, a line break.
#[test]
fn doc_literals_print_as_escaped_strings_do() {
    let print = |lit: Literal| {
        let file: syn::File = syn::parse2(quote!(#[doc = #lit] pub struct S;)).unwrap();
        prettyplease::unparse(&file)
    };
    for text in [
        " plain",
        " say \"hi\"",
        " a \"# and \"## in it",
        " back\\slash \\n and \\\\",
        " 25 \u{b0}C, \u{a7}4.2, \u{b5}s, tab\there",
        " two\nlines",
        "/ starts with a slash",
        " carriage\rreturn",
    ] {
        assert_eq!(
            print(doc_lit(text)),
            print(Literal::string(text)),
            "{text:?}"
        );
    }
    assert!(doc_lit(" a \"# b").to_string().starts_with("r##\""));
}

/// Brackets of document text are escaped, the generator's own ``[`Name`]`` links are not.
#[test]
fn brackets_are_escaped_but_links_kept() {
    for (line, escaped) in [
        ("no brackets", "no brackets"),
        ("0.02 [A]", "0.02 \\[A\\]"),
        ("see [`Name`]", "see [`Name`]"),
        ("[`a` b]`[x]", "[`a` b\\]`\\[x\\]"),
        ("][", "\\]\\["),
    ] {
        assert_eq!(escape_brackets(line), escaped, "{line:?}");
    }
}

/// Type names: snake_case words joined capitalised, empty words skipped; integer types by
/// width and sign, a 24-bit one held in 32 bits.
#[test]
fn type_names() {
    for (snake, name) in [
        ("read_status", "ReadStatus"),
        ("_a__b_", "AB"),
        ("x", "X"),
        ("", ""),
        ("set_2nd_µs", "Set2ndµs"),
    ] {
        assert_eq!(camel(snake), name, "{snake:?}");
    }
    for (bits, signed, name) in [
        (8, false, "u8"),
        (16, true, "i16"),
        (24, false, "u32"),
        (24, true, "i32"),
        (64, true, "i64"),
        (128, false, "u128"),
    ] {
        assert_eq!(
            IntType {
                bits,
                signed,
                float: false
            }
            .ident()
            .to_string(),
            name
        );
    }
}

#[test]
fn a_record_named_like_another_type_is_refused_by_name() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/fixtures/valid/records.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    // `sync_write.blocks` would be `SyncWriteBlocks`, a unit's name here.
    let clash = text.replace(
        "  - {name: count, symbol: \"\", scale: \"1\"}",
        "  - {name: count, symbol: \"\", scale: \"1\"}\n  - {name: sync_write_blocks, symbol: \"\", scale: \"2\"}",
    );
    let p = busspec_model::load_str("records.yaml", &clash).unwrap_or_else(|d| panic!("{d}"));
    let e = super::emit_module(&p, "records.yaml", "records.yaml").unwrap_err();
    assert!(
        e.contains("`sync_write.blocks` would be the struct `SyncWriteBlocks`, the name of the unit `sync_write_blocks`"),
        "{e}"
    );
    let p = busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"));
    assert!(super::emit_module(&p, "records.yaml", "records.yaml").is_ok());
}

/// A field's descriptor is a constant of its message's struct, the field's name upper-cased
/// with `_DESC` after it, the same constant each time the field is named; where another of the
/// struct's constants takes that name (the byte range of a field `quantity_desc`), `__DESC`.
#[test]
fn a_field_descriptor_never_takes_another_constants_name() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../spec/modbus.yaml");
    let p = busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"));
    let ctx = Ctx::new(&p);
    let read_coils = &p.commands[0];
    assert_eq!(read_coils.name, "read_coils");
    let quantity = quote!(&request::ReadCoils::QUANTITY_DESC).to_string();
    assert_eq!(ctx.field_desc(read_coils, "quantity").to_string(), quantity);
    // A field called `quantity_desc` takes `QUANTITY_DESC` for its byte range.
    let mut read = read_coils.clone();
    read.name = "read".into();
    read.fields[1].name = "quantity_desc".into();
    assert_eq!(
        ctx.field_desc(&read, "quantity").to_string(),
        quote!(&request::Read::QUANTITY__DESC).to_string()
    );
    assert_eq!(ctx.field_desc(read_coils, "quantity").to_string(), quantity);
    let reply = &p.responses[0];
    assert_eq!(
        ctx.field_desc(reply, "coils").to_string(),
        quote!(&response::ReadCoilsReply::COILS_DESC).to_string()
    );
    assert_eq!(ctx.field_descs.borrow().len(), 3);
}

/// A view lends the frame's own bytes: where the decoder reads a copy (escaping, the long
/// length form) there is none, and the module's docs say why; a plain variable-length spec has
/// both.
#[test]
fn views_only_where_the_decoder_reads_the_frame_itself() {
    let load = |name: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../model/tests/fixtures/valid")
            .join(name);
        busspec_model::load_file(&path).unwrap_or_else(|d| panic!("{d}"))
    };
    for (file, why) in [
        ("cobs_link.yaml", "escaped"),
        ("dynamixel2_stuffed.yaml", "escaped"),
        ("vesc.yaml", "long length form"),
        ("mbus.yaml", "short form"),
    ] {
        let p = load(file);
        assert!(no_view(&p, Direction::Request).is_some_and(|w| w.contains(why)));
        assert!(no_view(&p, Direction::Response).is_some_and(|w| w.contains(why)));
        let code = emit_module(&p, file, file).unwrap();
        assert!(!code.contains("View<'a>"), "{file}");
        assert!(code.contains("Borrowed views: no `RequestView`"), "{file}");
    }
    let p = load("minimal_variable.yaml");
    assert_eq!(no_view(&p, Direction::Request), None);
    assert_eq!(no_view(&p, Direction::Response), None);
    let code = emit_module(&p, "v", "v").unwrap();
    assert!(
        code.contains("pub enum RequestView<'a>") && code.contains("pub enum ResponseView<'a>")
    );
    // A type of the spec named as a view would be is refused, naming it.
    let mut p = p;
    p.units[0].name = "request_view".into();
    let e = emit_module(&p, "v", "v").unwrap_err();
    assert!(e.contains("`RequestView`"), "{e}");
}
