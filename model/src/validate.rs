//! Spec model to IR: resolve every reference, lay out every frame, check every rule, and replay
//! every example through the interpreter. All problems are collected, each with its path.

use std::collections::{BTreeMap, BTreeSet};

use crate::checksum;
use crate::diag::{join, Sink};
use crate::interp::{self, raw_limits, Raw};
use crate::ir::*;
use crate::model;
use crate::rational::Rational;

/// Rust keywords (2021 edition, strict and reserved): a spec name must not be one, since names
/// become identifiers in generated code.
const KEYWORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern",
    "false", "fn", "for", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub",
    "ref", "return", "self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use",
    "where", "while", "abstract", "become", "box", "do", "final", "gen", "macro", "override",
    "priv", "try", "typeof", "unsized", "virtual", "yield", "union",
];

/// Checks that `name` is a lower snake_case identifier usable in generated code.
pub fn check_ident(name: &str, path: &str, what: &str, sink: &mut Sink) -> bool {
    let mut chars = name.chars();
    let ok_start = chars.next().is_some_and(|c| c.is_ascii_lowercase());
    let ok_rest = chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    if !ok_start || !ok_rest {
        sink.error(
            path,
            format!("{what} `{name}` is not a valid identifier: use lower snake_case, starting with a letter ([a-z][a-z0-9_]*)"),
        );
        return false;
    }
    if KEYWORDS.contains(&name) {
        sink.error(
            path,
            format!("{what} `{name}` is a Rust keyword and cannot name generated code"),
        );
        return false;
    }
    true
}

fn fits_unsigned(v: i64, bits: u32) -> bool {
    let (_, max) = raw_limits(bits, false);
    v >= 0 && v <= max
}

/// `0x1FF` for a value written as a wire constant; a negative one stays decimal (`-1`), where
/// `{:X}` would print its two's complement (`0xFFFFFFFFFFFFFFFF`).
fn hex_or_negative(v: i64) -> String {
    if v < 0 {
        v.to_string()
    } else {
        format!("0x{v:X}")
    }
}

fn u8_of(v: i64, path: &str, what: &str, sink: &mut Sink) -> u8 {
    if !(0..=255).contains(&v) {
        sink.error(
            path,
            format!("{what} {v} does not fit in one byte (0..=255)"),
        );
        return 0;
    }
    v as u8
}

fn text(o: &Option<String>) -> String {
    o.clone().unwrap_or_default()
}

/// Resolves names to indices and reports duplicates.
struct Names {
    map: BTreeMap<String, usize>,
}

impl Names {
    fn build<'a>(
        items: impl Iterator<Item = &'a str>,
        list: &str,
        what: &str,
        sink: &mut Sink,
    ) -> Names {
        let mut map = BTreeMap::new();
        for (i, name) in items.enumerate() {
            let path = join(list, name);
            check_ident(name, &path, what, sink);
            if map.insert(name.to_owned(), i).is_some() {
                sink.error(path, format!("duplicate {what} name `{name}`"));
            }
        }
        Names { map }
    }

    fn get(&self, name: &str) -> Option<usize> {
        self.map.get(name).copied()
    }
}

pub fn validate(spec: &model::Spec, sink: &mut Sink) -> Option<Protocol> {
    // Constant whole frames (`frame:`) come after every framed response in the IR, so each
    // direction's framed messages are a prefix of its list ([`Protocol::framed`]); errors
    // are located by name, so the order changes none of them.
    if spec.responses.iter().any(|r| r.frame.is_some()) {
        let mut spec = spec.clone();
        spec.responses.sort_by_key(|r| r.frame.is_some());
        return validate_ordered(&spec, sink);
    }
    validate_ordered(spec, sink)
}

fn validate_ordered(spec: &model::Spec, sink: &mut Sink) -> Option<Protocol> {
    check_ident(&spec.protocol, "protocol", "protocol name", sink);
    if spec.title.trim().is_empty() {
        sink.error("title", "title is empty");
    }
    for (key, v) in [
        ("revision", &spec.document.revision),
        ("date", &spec.document.date),
        ("title", &spec.document.title),
    ] {
        if v.trim().is_empty() {
            sink.error(join("document", key), format!("document {key} is empty"));
        }
    }

    let units = units(spec, sink);
    let enum_names = Names::build(
        spec.enums.iter().map(|e| e.name.as_str()),
        "enums",
        "enum",
        sink,
    );
    let enums = enums(spec, sink);
    let flag_names = Names::build(
        spec.flags.iter().map(|f| f.name.as_str()),
        "flags",
        "flag set",
        sink,
    );
    let flags = flag_sets(spec, sink);
    let unit_names = Names::build(
        spec.units.iter().map(|u| u.name.as_str()),
        "units",
        "unit",
        sink,
    );

    let serial = Serial {
        section: spec.serial.section.clone(),
        baud: spec.serial.baud,
        data_bits: spec.serial.data_bits,
        parity: spec.serial.parity,
        stop_bits: spec.serial.stop_bits,
        inter_frame_gap_ms: spec.serial.inter_frame_gap_ms,
        frame_rate: spec.serial.frame_rate.clone(),
        baud_rates: spec.serial.baud_rates.as_ref().and_then(|n| {
            let r = enum_names.get(n);
            if r.is_none() {
                sink.error(
                    "serial.baud_rates",
                    format!("refers to enum `{n}`, which is not defined"),
                );
            }
            r
        }),
    };
    if spec.serial.baud == 0 {
        sink.error("serial.baud", "baud rate must be positive");
    }
    if !(5..=9).contains(&spec.serial.data_bits) {
        sink.error(
            "serial.data_bits",
            format!("{} data bits: expected 5..=9", spec.serial.data_bits),
        );
    }
    if !(1..=2).contains(&spec.serial.stop_bits) {
        sink.error(
            "serial.stop_bits",
            format!("{} stop bits: expected 1 or 2", spec.serial.stop_bits),
        );
    }

    let refs = Refs {
        units: &unit_names,
        enums: &enum_names,
        flags: &flag_names,
        enum_defs: &enums,
        flag_defs: &flags,
        unit_defs: &units,
    };
    let mut framing = framing(&spec.framing, spec.byte_order, &refs, sink);

    // Commands and responses share one name space: examples refer to either by name.
    let all_names = spec
        .commands
        .iter()
        .map(|c| c.name.as_str())
        .chain(spec.responses.iter().map(|r| r.name.as_str()));
    let mut seen = BTreeSet::new();
    for (i, name) in all_names.enumerate() {
        let list = if i < spec.commands.len() {
            "commands"
        } else {
            "responses"
        };
        let path = join(list, name);
        check_ident(name, &path, "message", sink);
        if !seen.insert(name) {
            sink.error(
                path,
                format!(
                    "duplicate message name `{name}` (commands and responses share one name space)"
                ),
            );
        }
    }
    let response_names = Names {
        map: spec
            .responses
            .iter()
            .enumerate()
            .map(|(i, r)| (r.name.clone(), i))
            .collect(),
    };
    let command_names = Names {
        map: spec
            .commands
            .iter()
            .enumerate()
            .map(|(i, c)| (c.name.clone(), i))
            .collect(),
    };

    let mut common = Vec::new();
    let mut is_common = vec![false; spec.responses.len()];
    for (i, name) in spec.common_responses.iter().enumerate() {
        let path = format!("common_responses[{i}]");
        match response_names.get(name) {
            Some(r) if is_common[r] => sink.error(path, format!("response `{name}` listed twice")),
            Some(r) => {
                is_common[r] = true;
                common.push(r);
            }
            None => sink.error(path, missing_response(name, &command_names)),
        }
    }

    let mut commands = Vec::new();
    for c in &spec.commands {
        let path = join("commands", &c.name);
        let (code, fields, payload_len, max_payload) = message_body(
            Some(&c.code),
            &c.fields,
            &c.header,
            &path,
            Direction::Request,
            &framing,
            spec.byte_order,
            &refs,
            sink,
        );
        let mut responses: Vec<(usize, Option<String>)> = Vec::new();
        // Where each response sits in `responses`: a list may be long, and is looked up often.
        let mut slot_of: std::collections::HashMap<usize, usize> = Default::default();
        for (i, name) in c.responses.iter().enumerate() {
            let rpath = format!("{path}.responses[{i}]");
            match response_names.get(name) {
                Some(r) if slot_of.contains_key(&r) || is_common[r] => {
                    sink.error(rpath, format!("response `{name}` listed twice (common responses apply to every command already)"))
                }
                Some(r) => {
                    slot_of.insert(r, responses.len());
                    responses.push((r, None));
                }
                None => sink.error(rpath, missing_response(name, &command_names)),
            }
        }
        // A command that gets no reply gets no common response either.
        let common: &[usize] = if c.reply == model::Reply::None {
            &[]
        } else {
            &common
        };
        for &r in common {
            if !c.response_meanings.is_empty() {
                slot_of.insert(r, responses.len());
            }
            responses.push((r, None));
        }
        for (k, v) in &c.response_meanings {
            let mpath = join(&path, "response_meanings");
            let (Some(k), Some(v)) = (k.as_str(), v.as_str()) else {
                sink.error(mpath, "response_meanings maps response names to text");
                continue;
            };
            match response_names
                .get(k)
                .and_then(|r| slot_of.get(&r))
                .and_then(|&at| responses.get_mut(at))
            {
                Some(slot) => slot.1 = Some(v.to_owned()),
                None => sink.error(
                    join(&mpath, k),
                    format!("`{k}` is not one of this command's responses"),
                ),
            }
        }
        match c.reply {
            model::Reply::None if !c.responses.is_empty() => sink.error(
                join(&path, "responses"),
                "a command with `reply: none` gets no response: list none",
            ),
            model::Reply::None if c.broadcast.as_ref().is_some_and(|b| b.answered) => sink.error(
                join(&path, "broadcast"),
                "a command with `reply: none` is not answered on broadcast either",
            ),
            model::Reply::None => {}
            _ if c.responses.is_empty() && common.is_empty() => sink.error(
                join(&path, "responses"),
                "a command must list the responses it may get (or say `reply: none`)",
            ),
            _ => {}
        }
        if c.broadcast.is_some() && !framing.has_address_in(Direction::Request) {
            sink.error(
                join(&path, "broadcast"),
                "requests carry no address (their layout has no `address`): none is a broadcast",
            );
        } else if c.broadcast.is_some() && framing.address.broadcast.is_none() {
            sink.error(
                join(&path, "broadcast"),
                "the protocol has no broadcast address (framing.address.broadcast)",
            );
        }
        if let Some(b) = &c.broadcast {
            if b.answered && !b.accepted {
                sink.error(
                    join(&path, "broadcast"),
                    "a broadcast that is not accepted cannot be answered",
                );
            }
        }
        check_section(&c.section, &path, sink);
        let layout = frame_layout(&framing, Direction::Request, code.len(), payload_len);
        check_length_fits(
            &framing,
            Direction::Request,
            &path,
            code.len(),
            max_payload,
            sink,
        );
        commands.push(Message {
            name: c.name.clone(),
            title: c.title.clone(),
            section: c.section.clone(),
            doc: text(&c.doc),
            direction: Direction::Request,
            kind: MessageKind::Command(c.kind),
            code,
            fields,
            payload_len,
            layout,
            responses,
            reply: c.reply,
            answers: Vec::new(),
            broadcast: c.broadcast.clone(),
            needs_request: false,
            code_from_request: None,
            max_len: layout.len + (max_payload - payload_len),
            checksum_extra: None,
            over_request: None,
            unchecked: false,
            frame: None,
            unasked: false,
        });
    }

    // The commands answered by each response, in command order: one pass over the commands.
    let mut answered_by: Vec<Vec<usize>> = vec![Vec::new(); spec.responses.len()];
    for (ci, c) in commands.iter().enumerate() {
        for &(r, _) in &c.responses {
            if let Some(list) = answered_by.get_mut(r) {
                if list.last() != Some(&ci) {
                    list.push(ci);
                }
            }
        }
    }
    let mut responses = Vec::new();
    let mut constants: Vec<(&str, Vec<u8>)> = Vec::new();
    for (ri, r) in spec.responses.iter().enumerate() {
        let path = join("responses", &r.name);
        if let Some(hex) = &r.frame {
            let answers = std::mem::take(&mut answered_by[ri]);
            if answers.is_empty() && !r.unasked {
                sink.error(&path, "no command lists this response (add it to a command's `responses` or to `common_responses`, or mark it `unasked: true` if the device sends it on its own)");
            }
            check_section(&r.section, &path, sink);
            let frame = constant_frame(r, hex, &framing, &constants, &path, sink);
            constants.push((&r.name, frame.clone()));
            let len = frame.len();
            responses.push(Message {
                name: r.name.clone(),
                title: r.title.clone(),
                section: r.section.clone(),
                doc: text(&r.doc),
                direction: Direction::Response,
                kind: MessageKind::Response(r.kind),
                code: Vec::new(),
                fields: Vec::new(),
                payload_len: 0,
                layout: FrameLayout {
                    start: None,
                    start_again: None,
                    length: None,
                    length_again: None,
                    address: None,
                    headers: [0; MAX_HEADER_PARTS],
                    code: 0,
                    payload: 0,
                    checksum: len,
                    len,
                },
                responses: Vec::new(),
                reply: model::Reply::Required,
                answers,
                broadcast: None,
                needs_request: false,
                code_from_request: None,
                max_len: len,
                checksum_extra: None,
                over_request: None,
                unchecked: false,
                frame: Some(frame),
                unasked: r.unasked,
            });
            continue;
        }
        let (code, fields, payload_len, max_payload) = message_body(
            r.code.as_deref().or_else(|| {
                sink.error(&path, "missing field `code` (a response without one is a constant whole frame: `frame`)");
                None
            }),
            &r.fields,
            &r.header,
            &path,
            Direction::Response,
            &framing,
            spec.byte_order,
            &refs,
            sink,
        );
        let answers = std::mem::take(&mut answered_by[ri]);
        if answers.is_empty() && !r.unasked {
            sink.error(&path, "no command lists this response (add it to a command's `responses` or to `common_responses`, or mark it `unasked: true` if the device sends it on its own)");
        }
        check_section(&r.section, &path, sink);
        if r.unasked {
            check_unasked(r, &fields, &path, sink);
        }
        let code_from_request = code_from_request(r, &code, &answers, &commands, &path, sink);
        check_request_fields(&fields, &answers, &commands, &path, sink);
        let layout = frame_layout(&framing, Direction::Response, code.len(), payload_len);
        check_length_fits(
            &framing,
            Direction::Response,
            &path,
            code.len(),
            max_payload,
            sink,
        );
        responses.push(Message {
            name: r.name.clone(),
            title: r.title.clone(),
            section: r.section.clone(),
            doc: text(&r.doc),
            direction: Direction::Response,
            kind: MessageKind::Response(r.kind),
            code,
            fields,
            payload_len,
            layout,
            responses: Vec::new(),
            reply: model::Reply::Required,
            answers,
            broadcast: None,
            needs_request: r.needs_request,
            code_from_request,
            max_len: layout.len + (max_payload - payload_len),
            checksum_extra: None,
            over_request: None,
            unchecked: false,
            frame: None,
            unasked: r.unasked,
        });
    }
    checksum_extras(spec, &mut framing, &mut commands, &mut responses, sink);
    unchecked_messages(spec, &framing, &mut commands, &mut responses, sink);
    over_requests(spec, &framing, &mut responses, sink);
    transform_lists(&framing, &commands, "commands", sink);
    transform_lists(&framing, &responses, "responses", sink);
    terminated_apart(&framing, &commands, "commands", sink);
    terminated_apart(&framing, &responses, "responses", sink);
    truncated_messages(&framing, &commands, "commands", sink);
    truncated_messages(&framing, &responses, "responses", sink);
    truncated_across(&framing, &commands, &responses, sink);
    if framing.long.is_some() && spec.printed_byte_order != spec.byte_order {
        sink.error(
            "printed_byte_order",
            "examples printed in another byte order beside a long length form (framing.length.long) are not expressible yet",
        );
    }
    if framing.truncation.is_some() && spec.printed_byte_order != spec.byte_order {
        sink.error(
            "printed_byte_order",
            "examples printed in another byte order beside payload truncation (framing.truncation) are not expressible yet",
        );
    }
    if framing.form.is_some() && spec.printed_byte_order != spec.byte_order {
        sink.error(
            "printed_byte_order",
            "examples printed in another byte order beside a frame form (framing.forms) are not expressible yet",
        );
    }
    if framing.long.is_some() {
        for m in responses.iter().filter(|m| m.frame.is_some()) {
            sink.error(
                format!("responses.{}.frame", m.name),
                "a constant whole frame beside a long length form (framing.length.long) is not expressible yet",
            );
        }
    }

    optional_codes(&commands, "commands", sink);
    optional_codes(&responses, "responses", sink);
    check_overlaps(&commands, "commands", sink);
    let framed = responses.len() - constants.len();
    check_overlaps(&responses[..framed], "responses", sink);
    // Constant frames' lengths among them: the generated stream decoder lists those too.
    let mut lengths: Vec<usize> = commands
        .iter()
        .chain(&responses)
        .filter(|m| !m.is_variable())
        .map(|m| m.layout.len)
        .collect();
    lengths.sort_unstable();
    lengths.dedup();
    if lengths.len() > MAX_DISTINCT_LENGTHS {
        sink.error(
            "framing",
            format!(
                "messages have {} distinct frame lengths; the generated stream decoder tracks at most {MAX_DISTINCT_LENGTHS}",
                lengths.len()
            ),
        );
    }

    let mut errata = Vec::new();
    let mut ids = BTreeSet::new();
    for e in &spec.errata {
        let path = join("errata", &e.id);
        if !ids.insert(e.id.as_str()) {
            sink.error(&path, format!("duplicate erratum id `{}`", e.id));
        }
        for (key, v) in [
            ("says", &e.says),
            ("decision", &e.decision),
            ("why", &e.why),
            ("section", &e.section),
        ] {
            if v.trim().is_empty() {
                sink.error(join(&path, key), format!("erratum {key} is empty"));
            }
        }
        errata.push(Erratum {
            id: e.id.clone(),
            section: e.section.clone(),
            says: e.says.clone(),
            decision: e.decision.clone(),
            why: e.why.clone(),
        });
    }

    let transactions = crate::transactions::validate(
        spec.transactions.as_ref(),
        &spec.serial,
        &spec.commands,
        sink,
    );
    if !sink.is_empty() {
        return None;
    }
    let mut proto = Protocol {
        name: spec.protocol.clone(),
        title: spec.title.clone(),
        document: spec.document.clone(),
        byte_order: spec.byte_order,
        printed_byte_order: spec.printed_byte_order,
        serial,
        framing,
        units,
        enums,
        flags,
        commands,
        responses,
        common_responses: common,
        examples: Vec::new(),
        errata,
        transactions,
        device: crate::device::Device::default(),
        spec_sha256: String::new(),
    };
    proto.examples = examples(spec, &proto, sink);
    proto.device = crate::device::validate(spec.device.as_ref(), &proto, sink);
    sink.is_empty().then_some(proto)
}

/// `framing.checksum.extra: per_message` and each message's `checksum_extra` (MAVLink's
/// CRC_EXTRA): the byte a CRC takes after the covered bytes, found by the code those bytes
/// hold. The code must be covered, sit at one place (every code one length, no escaping to
/// move it) and name one byte whichever direction has it.
fn checksum_extras(
    spec: &model::Spec,
    framing: &mut Framing,
    commands: &mut [Message],
    responses: &mut [Message],
    sink: &mut Sink,
) {
    let path = "framing.checksum.extra";
    // Each message's byte as the spec gives it, commands then responses.
    let declared = [
        (
            "commands",
            spec.commands
                .iter()
                .map(|c| c.checksum_extra)
                .collect::<Vec<_>>(),
        ),
        (
            "responses",
            spec.responses.iter().map(|r| r.checksum_extra).collect(),
        ),
    ];
    let Some(model::ChecksumExtra::PerMessage) =
        spec.framing.checksum.as_ref().and_then(|c| c.extra)
    else {
        for ((list, xs), ms) in declared.iter().zip([&*commands, &*responses]) {
            for (m, x) in ms.iter().zip(xs) {
                if x.is_some() {
                    sink.error(
                        format!("{list}.{}.checksum_extra", m.name),
                        "a message's checksum extra byte needs `framing.checksum.extra: per_message`",
                    );
                }
            }
        }
        return;
    };
    let errors = sink.items.len();
    if !matches!(framing.checksum.algorithm, ChecksumAlgorithm::Crc(_)) {
        sink.error(
            path,
            "an extra byte per message is taken by a CRC only (MAVLink's CRC_EXTRA)",
        );
    }
    if framing.escaping.is_some() {
        sink.error(
            path,
            "not with `escaping`: the code's place in the bytes the checksum covers would move",
        );
    }
    let lens = all_code_lengths(
        &framing.request.code_lengths,
        &framing.response.code_lengths,
    );
    let code_len = lens.first().copied().unwrap_or(0);
    let head = framing.head(Direction::Request, code_len);
    let code_at = head.code;
    if framing.head(Direction::Response, code_len).code != code_at {
        sink.error(
            path,
            "the code sits at another offset in each direction's layout: an extra byte per message is not expressible with it yet",
        );
    }
    match lens.as_slice() {
        [n] if *n > 0 => {}
        _ => sink.error(
            path,
            format!("the extra byte is found by the code, so every message needs a code of one length; code_lengths give {lens:?}"),
        ),
    }
    if framing.checksum.covers_by_direction() {
        sink.error(
            path,
            "the checksum covers from another offset in each direction: an extra byte per message is not expressible with it yet",
        );
    }
    if code_at < framing.checksum.covers_from {
        sink.error(
            path,
            "the checksum must cover the code, by which its extra byte is found",
        );
    }
    let mut by_code: Vec<(Vec<u8>, u8, String)> = Vec::new();
    for ((list, xs), ms) in declared.into_iter().zip([commands, responses]) {
        for (m, x) in ms.iter_mut().zip(xs) {
            let at = format!("{list}.{}.checksum_extra", m.name);
            let Some(x) = x else {
                sink.error(
                    at,
                    "missing: `framing.checksum.extra: per_message` wants each message's byte",
                );
                continue;
            };
            let x = u8_of(x, &at, "a checksum extra byte", sink);
            if m.code_from_request.is_some() {
                sink.error(
                    at,
                    "not with `code_from_request`: the code is the request's",
                );
                continue;
            }
            match by_code.iter().find(|(c, _, _)| *c == m.code) {
                Some((_, y, first)) if *y != x => sink.error(
                    at,
                    format!("{x} differs from {y}, {first}'s, which has the same code: the extra byte is found by the code"),
                ),
                Some(_) => {}
                None => by_code.push((m.code.clone(), x, m.name.clone())),
            }
            m.checksum_extra = Some(x);
        }
    }
    if sink.items.len() == errors {
        framing.checksum.extra = Some(ChecksumExtra {
            code_at: head.code - framing.checksum.covers_from,
            by_code: by_code.into_iter().map(|(c, x, _)| (c, x)).collect(),
        });
    }
}

/// Whether frames of `a` and `b` are told apart by code and length alone, before any
/// checksum is checked: their lengths cannot meet (from the shortest frame each can have: text
/// up to a terminator has its terminator at least), their codes differ where both sit, or one
/// is a constant whole frame.
fn told_apart(a: &Message, b: &Message) -> bool {
    let overlap = a.min_len() <= b.max_len && b.min_len() <= a.max_len;
    let coded = !a.code.is_empty()
        && a.code.len() == b.code.len()
        && a.layout.code == b.layout.code
        && a.code != b.code;
    !overlap || coded || a.frame.is_some() || b.frame.is_some()
}

/// Messages that travel without the framing's checksum (`checksum: none`): their layout ends
/// where the checksum would begin. Each has one length and is told apart from every message
/// with a checksum by its code and length alone, which is how both engines find it before any
/// checksum is checked.
fn unchecked_messages(
    spec: &model::Spec,
    framing: &Framing,
    commands: &mut [Message],
    responses: &mut [Message],
    sink: &mut Sink,
) {
    let clen = framing.checksum.len();
    let given = spec
        .commands
        .iter()
        .map(|c| (c.checksum, c.checksum_extra.is_some(), false, false))
        .zip(commands.iter_mut().map(|m| ("commands", m)))
        .chain(
            spec.responses
                .iter()
                .map(|r| {
                    (
                        r.checksum,
                        r.checksum_extra.is_some(),
                        r.checksum_over_request.is_some(),
                        r.frame.is_some(),
                    )
                })
                .zip(responses.iter_mut().map(|m| ("responses", m))),
        );
    // Every message that leaves its checksum out, refused or not: none of them is one that
    // carries a checksum to tell the others from.
    let mut asked: Vec<(Direction, String)> = Vec::new();
    for ((checksum, extra, over, constant), (list, m)) in given {
        if checksum.is_none() || constant {
            continue;
        }
        asked.push((m.direction, m.name.clone()));
        let path = format!("{list}.{}.checksum", m.name);
        let errors = sink.items.len();
        if framing.checksum.is_empty() {
            sink.error(&path, "the framing has no checksum to leave out");
        }
        for (given, what) in [
            (framing.escaping.is_some(), "escaping (`framing.escaping`)"),
            (
                framing.transform.is_some(),
                "a transform (`framing.transform`)",
            ),
            (
                framing.length.is_some(),
                "a length field (`framing.length`)",
            ),
            (
                framing.long.is_some(),
                "a long length form (`framing.length.long`)",
            ),
            (framing.form.is_some(), "a short form (`framing.forms`)"),
            (framing.truncation.is_some(), "payload truncation"),
            (!framing.end.is_empty(), "end bytes (`framing.end`)"),
            (
                framing.preamble.is_some(),
                "a preamble (`framing.preamble`)",
            ),
            (extra, "its own `checksum_extra`"),
            (over, "`checksum_over_request`"),
            (
                framing.checksum.lead.is_some(),
                "a checksum before the payload",
            ),
        ] {
            if given {
                sink.error(
                    &path,
                    format!("a message without a checksum is not expressible beside {what} yet"),
                );
            }
        }
        if m.max_len != m.layout.len {
            sink.error(
                &path,
                "a message without a checksum has one length yet: it takes no repeated or optional field",
            );
        }
        if framing.direction(m.direction).code_lengths.len() > 1 {
            sink.error(
                &path,
                "a message without a checksum beside several code lengths in its direction is not expressible yet",
            );
        }
        // Its frame without the checksum: no start byte, address, code or field leaves nothing
        // on the wire to find, tell apart or decode.
        if m.layout.len <= clen {
            sink.error(
                &path,
                "without its checksum the message's frame holds no byte (no start byte, address, code or field): nothing would travel",
            );
        }
        if sink.items.len() == errors {
            m.unchecked = true;
            m.layout.len -= clen;
            m.max_len -= clen;
        }
    }
    // Told apart by code and length alone from every message with a checksum.
    let all: Vec<&Message> = commands.iter().chain(responses.iter()).collect();
    for m in all.iter().filter(|m| m.unchecked) {
        let clash = all.iter().find(|x| {
            !x.unchecked
                && !asked.iter().any(|(d, n)| *d == x.direction && *n == x.name)
                && !told_apart(m, x)
        });
        if let Some(x) = clash {
            let list = match m.direction {
                Direction::Request => "commands",
                Direction::Response => "responses",
            };
            sink.error(
                format!("{list}.{}.checksum", m.name),
                format!(
                    "{} can have the same code and length, and carries a checksum: a message without one must be told apart by its code and length alone",
                    x.name
                ),
            );
        }
    }
}

/// Each response's `checksum_over_request`: where in its frame its checksum takes up its own
/// bytes after its request's. A frame is known to be such a reply before its checksum is
/// checked, by its code and length alone (both engines check the checksum before they look
/// at the fields), so no other response of another rule may share a code and a length with
/// it; a request may, its own checksum checked for the request's reading.
fn over_requests(
    spec: &model::Spec,
    framing: &Framing,
    responses: &mut [Message],
    sink: &mut Sink,
) {
    for (r, m) in spec.responses.iter().zip(responses.iter_mut()) {
        let Some(over) = &r.checksum_over_request else {
            continue;
        };
        if m.frame.is_some() {
            continue;
        }
        let path = format!("responses.{}.checksum_over_request", m.name);
        let errors = sink.items.len();
        if framing.checksum.is_empty() {
            sink.error(
                &path,
                "the framing has no checksum to take in the request's bytes",
            );
        }
        for (given, what) in [
            (framing.escaping.is_some(), "escaping (`framing.escaping`)"),
            (
                framing.transform.is_some(),
                "a transform (`framing.transform`)",
            ),
            (
                framing.long.is_some(),
                "a long length form (`framing.length.long`)",
            ),
            (framing.form.is_some(), "a short form (`framing.forms`)"),
            (framing.truncation.is_some(), "payload truncation"),
            (
                framing.checksum.extra.is_some(),
                "an extra checksum byte per message",
            ),
            (
                framing.preamble.is_some(),
                "a preamble (`framing.preamble`)",
            ),
            (
                framing.checksum.lead.is_some(),
                "a checksum before the payload",
            ),
        ] {
            if given {
                sink.error(
                    &path,
                    format!(
                        "a checksum over the request's bytes is not expressible beside {what} yet"
                    ),
                );
            }
        }
        let part = over.covers_from;
        let o = m.layout;
        let at = match part {
            Part::Start => o.start,
            Part::Address => o.address,
            Part::Length => o.length,
            Part::Header => Some(o.headers[0]),
            Part::Code => Some(o.code),
            Part::Payload => Some(o.payload),
            Part::Checksum | Part::End => None,
        };
        match at {
            Some(at) if framing.layout_of(Direction::Response).contains(&part) => {
                if sink.items.len() == errors {
                    m.over_request = Some(at);
                }
            }
            _ => sink.error(
                join(&path, "covers_from"),
                format!(
                    "the checksum cannot cover from `{}`: name a part of the response's layout before the checksum",
                    part_name(part)
                ),
            ),
        }
    }
    // Told apart by code and length alone from every message of another rule.
    let apart = told_apart;
    for (i, m) in responses.iter().enumerate() {
        if m.over_request.is_none() {
            continue;
        }
        // Requests may share it: decoded both ways, each direction is checked by its own
        // rule (a request's checksum, the reply's over its request).
        let others = responses
            .iter()
            .enumerate()
            .filter(|&(j, x)| {
                x.over_request != m.over_request && (x.over_request.is_none() || j > i)
            })
            .map(|(_, x)| x);
        for x in others {
            if !apart(m, x) {
                sink.error(
                    format!("responses.{}.checksum_over_request", m.name),
                    format!(
                        "{} can have the same code and length, and its checksum covers other bytes: a reply whose checksum takes in its request's bytes must be told apart by its code and length alone",
                        x.name
                    ),
                );
                break;
            }
        }
    }
}

/// A response sent unasked (`unasked: true`) must read without a request: nothing of it may
/// come from one.
fn check_unasked(r: &model::Response, fields: &[Field], path: &str, sink: &mut Sink) {
    let why = "a response sent unasked (`unasked: true`) must decode without a request";
    if r.needs_request {
        sink.error(
            join(path, "needs_request"),
            format!("{why}; it cannot need one to be told apart"),
        );
    }
    if r.code_from_request.is_some() {
        sink.error(
            join(path, "code_from_request"),
            format!("{why}; its code cannot derive from the request's"),
        );
    }
    if r.checksum_over_request.is_some() {
        sink.error(
            join(path, "checksum_over_request"),
            format!("{why}; its checksum cannot take in the request's bytes"),
        );
    }
    for f in fields {
        let key = match (
            &f.follows,
            f.repeat.as_ref().and_then(|r| r.request.as_ref()),
        ) {
            (Some(Follows::Request(_)), _) => "follows",
            (_, Some(_)) => "repeat.request",
            _ => continue,
        };
        sink.error(
            join(&join(&join(path, "fields"), &f.name), key),
            format!("{why}; `{}` cannot take its value from the request", f.name),
        );
    }
}

/// A reply's `code_from_request`: its code must be every answered command's code with those
/// bits set.
fn code_from_request(
    r: &model::Response,
    code: &[u8],
    answers: &[usize],
    commands: &[Message],
    path: &str,
    sink: &mut Sink,
) -> Option<u8> {
    let c = r.code_from_request.as_ref()?;
    let p = join(path, "code_from_request");
    let or = u8_of(c.or, &join(&p, "or"), "code bits", sink);
    if code.len() != 1 {
        sink.error(&p, "a code derived from the request's is one byte");
        return None;
    }
    for &i in answers {
        let cmd = &commands[i];
        match cmd.code.as_slice() {
            [b] if b | or == code[0] => {}
            _ => sink.error(
                &p,
                format!(
                    "answers `{}` ({}), whose code with 0x{or:02X} set is not this reply's 0x{:02X}",
                    cmd.name,
                    cmd.code_hex(),
                    code[0]
                ),
            ),
        }
    }
    Some(or)
}

/// Every field a reply takes from its request (`follows: {request}`, `repeat.request`) must be
/// a number field of every command it answers.
fn check_request_fields(
    fields: &[Field],
    answers: &[usize],
    commands: &[Message],
    path: &str,
    sink: &mut Sink,
) {
    for f in fields {
        let (rel, key) = match (
            &f.follows,
            f.repeat.as_ref().and_then(|r| r.request.as_ref()),
        ) {
            (Some(Follows::Request(rel)), _) => (rel, "follows"),
            (_, Some(rel)) => (rel, "repeat.request"),
            _ => continue,
        };
        for &i in answers {
            let cmd = &commands[i];
            let ok = cmd.fields.iter().any(|g| {
                g.name == rel.field
                    && g.bits.is_empty()
                    && !g.is_ascii()
                    && !g.is_wide()
                    && !g.bcd
                    && !g.is_list()
            });
            if !ok {
                sink.error(
                    join(&join(&join(path, "fields"), &f.name), key),
                    format!(
                        "`{}` answers `{}`, which has no number field `{}`",
                        f.name, cmd.name, rel.field
                    ),
                );
            }
        }
    }
}

/// A length field must be able to hold the longest frame's count.
fn check_length_fits(
    framing: &Framing,
    d: Direction,
    path: &str,
    code_len: usize,
    max_payload: usize,
    sink: &mut Sink,
) {
    let Some(l) = &framing.length else {
        return;
    };
    let most = framing.length_value_of(d, l, code_len, max_payload);
    let limit = (1i64 << (8 * l.width)) - 1;
    if most < 0 || most > limit {
        sink.error(
            path,
            format!(
                "the length field would say {most}, outside a {}-byte length's 0..={limit}",
                l.width
            ),
        );
    }
}

fn missing_response(name: &str, commands: &Names) -> String {
    if commands.get(name).is_some() {
        format!("`{name}` is a command, not a response")
    } else {
        format!("refers to response `{name}`, which is not defined")
    }
}

fn check_section(section: &str, path: &str, sink: &mut Sink) {
    if section.trim().is_empty() {
        sink.error(
            join(path, "section"),
            "section is empty: cite the document section",
        );
    }
}

fn units(spec: &model::Spec, sink: &mut Sink) -> Vec<Unit> {
    let mut out = Vec::new();
    for u in &spec.units {
        let path = join("units", &u.name);
        let scale = match Rational::parse(&u.scale.0) {
            Ok(s) if s.num > 0 => s,
            Ok(s) => {
                sink.error(
                    join(&path, "scale"),
                    format!("scale {s} must be greater than zero"),
                );
                Rational::ONE
            }
            Err(e) => {
                sink.error(join(&path, "scale"), format!("bad scale: {e}"));
                Rational::ONE
            }
        };
        let offset = match u.offset.as_ref().map(|o| Rational::parse(&o.0)) {
            None => Rational::ZERO,
            Some(Ok(o)) => o,
            Some(Err(e)) => {
                sink.error(join(&path, "offset"), format!("bad offset: {e}"));
                Rational::ZERO
            }
        };
        if u.symbol.chars().any(char::is_control) {
            sink.error(
                join(&path, "symbol"),
                "unit symbol contains control characters",
            );
        }
        out.push(Unit {
            name: u.name.clone(),
            symbol: u.symbol.clone(),
            scale,
            offset,
            doc: text(&u.doc),
        });
    }
    out
}

fn enums(spec: &model::Spec, sink: &mut Sink) -> Vec<Enum> {
    let mut out = Vec::new();
    for e in &spec.enums {
        let path = join("enums", &e.name);
        if e.values.is_empty() {
            sink.error(join(&path, "values"), "an enum needs at least one value");
        }
        let _ = Names::build(
            e.values.iter().map(|v| v.name.as_str()),
            &join(&path, "values"),
            "enum value",
            sink,
        );
        let mut seen = BTreeSet::new();
        let mut values = Vec::new();
        for v in &e.values {
            let vpath = join(&join(&path, "values"), &v.name);
            if v.value < 0 {
                sink.error(
                    &vpath,
                    format!(
                        "enum value {} is negative; enum values are raw unsigned wire values",
                        v.value
                    ),
                );
            } else if !seen.insert(v.value) {
                sink.error(
                    &vpath,
                    format!("value {} is used twice in enum `{}`", v.value, e.name),
                );
            }
            values.push(EnumValue {
                value: v.value.max(0) as u64,
                name: v.name.clone(),
                doc: text(&v.doc),
            });
        }
        out.push(Enum {
            name: e.name.clone(),
            section: e.section.clone(),
            doc: text(&e.doc),
            values,
        });
    }
    out
}

fn flag_sets(spec: &model::Spec, sink: &mut Sink) -> Vec<FlagSet> {
    let mut out = Vec::new();
    for f in &spec.flags {
        let path = join("flags", &f.name);
        let _ = Names::build(
            f.bits.iter().map(|b| b.name.as_str()),
            &join(&path, "bits"),
            "flag",
            sink,
        );
        let mut seen = BTreeSet::new();
        let mut bits = Vec::new();
        for b in &f.bits {
            let bpath = join(&join(&path, "bits"), &b.name);
            if !(0..64).contains(&b.bit) {
                sink.error(&bpath, format!("bit {} is outside 0..=63", b.bit));
            } else if !seen.insert(b.bit) {
                sink.error(
                    &bpath,
                    format!("bit {} is used twice in flag set `{}`", b.bit, f.name),
                );
            }
            bits.push(Flag {
                bit: b.bit.clamp(0, 63) as u8,
                name: b.name.clone(),
                doc: text(&b.doc),
            });
        }
        out.push(FlagSet {
            name: f.name.clone(),
            section: f.section.clone(),
            doc: text(&f.doc),
            bits,
        });
    }
    out
}

/// A layout part as the spec writes it.
/// Every code length of either direction, once each, shortest first.
fn all_code_lengths(request: &[usize], response: &[usize]) -> Vec<usize> {
    let mut lens: Vec<usize> = request.iter().chain(response).copied().collect();
    lens.sort_unstable();
    lens.dedup();
    lens
}

fn part_name(p: Part) -> &'static str {
    match p {
        Part::Start => "start",
        Part::Address => "address",
        Part::Length => "length",
        Part::Code => "code",
        Part::Payload => "payload",
        Part::Checksum => "checksum",
        Part::End => "end",
        Part::Header => "header",
    }
}

fn framing(f: &model::Framing, byte_order: ByteOrder, refs: &Refs, sink: &mut Sink) -> Framing {
    match &f.layout {
        model::Layout::Same(_) => framing_plain(f, byte_order, refs, sink),
        model::Layout::ByDirection(d) => framing_by_direction(f, d, byte_order, refs, sink),
    }
}

/// A layout per direction (`framing.layout: {request, response}`): each direction's layout
/// validated as a layout is (each a plain framing of its own, without the sections of the parts
/// it lacks where the other has them), the errors of both reported once, each layout's own at
/// `framing.layout.request` or `framing.layout.response`; the two framings joined into one
/// IR. What neither engine carries with a layout per direction yet is refused here.
fn framing_by_direction(
    f: &model::Framing,
    d: &model::DirectionLayout,
    byte_order: ByteOrder,
    refs: &Refs,
    sink: &mut Sink,
) -> Framing {
    let not_yet = |what: &str| {
        format!("{what} is not expressible with a layout per direction (`framing.layout: {{request, response}}`) yet")
    };
    if !f.forms.is_empty() {
        sink.error("framing.forms", not_yet("a short form of the frame"));
    }
    if f.length.as_ref().is_some_and(|l| l.long.is_some()) {
        sink.error("framing.length.long", not_yet("a long length form"));
    }
    if f.truncation.is_some() {
        sink.error("framing.truncation", not_yet("payload truncation"));
    }
    if f.preamble.is_some() {
        sink.error("framing.preamble", not_yet("a preamble"));
    }
    if f.transform.is_some() {
        sink.error("framing.transform", not_yet("a transform of the payload"));
    }
    // Responses without start and end bytes beside flagged requests (F.Port's uplink after
    // its 7E-flagged downlink): byte escaping, every response stuffed from its first byte to
    // its last and framed by its length field, the requests' flags among the escaped bytes
    // (checked once the framing is joined), both directions with a length field and a
    // checksum. Each engine finds a request between its flags and a response, at a byte that
    // is no start byte, by its length.
    let framed = |l: &[Part]| l.first() == Some(&Part::Start) && l.last() == Some(&Part::End);
    let bare = |l: &[Part]| !l.contains(&Part::Start) && !l.contains(&Part::End);
    let both = |l: &[Part]| l.contains(&Part::Length) && l.contains(&Part::Checksum);
    let bare_responses = f.escaping.as_ref().is_some_and(|e| e.escape.is_some())
        && framed(&d.request)
        && bare(&d.response)
        && both(&d.request)
        && both(&d.response);
    let mut escaping_refused = false;
    if let Some(e) = &f.escaping {
        let bytes = e.escape.is_some() || e.cobs == Some(true);
        if !bytes {
            sink.error("framing.escaping", not_yet("escaping by insertion"));
            escaping_refused = true;
        } else if bare_responses {
            // Responses framed by their length field, requests by their end byte.
        } else if !d.request.contains(&Part::End) || !d.response.contains(&Part::End) {
            sink.error(
                "framing.escaping",
                not_yet("escaping without an end byte (frames found by their length field)"),
            );
            escaping_refused = true;
        }
    }
    let lists = [("request", &d.request), ("response", &d.response)];
    for (name, list) in lists {
        for (part, pname) in [(Part::Start, "start"), (Part::Length, "length")] {
            if list.iter().filter(|p| **p == part).count() > 1 {
                sink.error(
                    format!("framing.layout.{name}"),
                    not_yet(&format!("a second `{pname}`")),
                );
            }
        }
    }
    // Parts that frame every frame (where it starts and ends, its length, its checksum) are
    // in both directions or in neither; the address and the header fields may be in one.
    for (part, pname) in [
        (Part::Start, "start"),
        (Part::Length, "length"),
        (Part::Checksum, "checksum"),
        (Part::End, "end"),
    ] {
        let (rq, rs) = (d.request.contains(&part), d.response.contains(&part));
        let flags = matches!(part, Part::Start | Part::End);
        if rq != rs && !(flags && bare_responses) {
            let lacks = if rq { "response" } else { "request" };
            // Start and end bytes in the requests alone are taken in one shape: say which.
            let taken = if flags {
                "; taken only for responses with neither start nor end bytes beside requests with both, byte-escaped (every request start and end byte among the escaped), with a length field and a checksum in both directions (F.Port's uplink beside its downlink)"
            } else {
                ""
            };
            sink.error(
                format!("framing.layout.{lacks}"),
                format!(
                    "the {lacks}'s layout has no `{pname}`, the other direction's has: {}{taken}",
                    not_yet(&format!("`{pname}` in one direction only"))
                ),
            );
        }
    }
    let at = |l: &[Part], p: Part| l.iter().position(|x| *x == p);
    for (name, l) in [("request", &d.request), ("response", &d.response)] {
        if matches!((at(l, Part::Checksum), at(l, Part::Payload)), (Some(c), Some(p)) if c < p) {
            sink.error(
                format!("framing.layout.{name}"),
                not_yet("a checksum before the payload with a layout per direction"),
            );
        }
    }
    let end_first = |l: &[Part]| matches!((at(l, Part::End), at(l, Part::Checksum)), (Some(e), Some(c)) if e < c);
    if end_first(&d.request) != end_first(&d.response) {
        sink.error(
            "framing.layout.response",
            not_yet("end bytes before the checksum in one direction and after it in the other"),
        );
    }
    let mut out: Vec<Framing> = Vec::new();
    for (name, list) in lists {
        let other = if name == "request" {
            &d.response
        } else {
            &d.request
        };
        let lacks = |p: Part| !list.contains(&p) && other.contains(&p);
        let mut own = f.clone();
        own.layout = model::Layout::Same(list.clone());
        // What is refused above is not validated again on each direction's own.
        own.forms = Vec::new();
        own.truncation = None;
        own.preamble = None;
        own.transform = None;
        if escaping_refused {
            own.escaping = None;
        }
        if let Some(l) = &mut own.length {
            l.long = None;
        }
        if lacks(Part::Address) {
            own.address = None;
        }
        if lacks(Part::Header) {
            own.header = None;
        }
        // Header fields per direction (`header: {request, response}`): each direction's own,
        // its errors located at the direction's key; none for a direction whose layout has
        // no `header` and whose list is empty.
        let header_by_direction = match &f.header {
            Some(h @ model::Header::ByDirection(_)) => {
                let fields = h.of(name == "request").clone();
                own.header = (!fields.is_empty() || list.contains(&Part::Header))
                    .then_some(model::Header::Same(fields));
                true
            }
            _ => false,
        };
        // Refused above where one direction lacks it: not reported again.
        if lacks(Part::Start) {
            own.start = None;
        }
        if lacks(Part::Length) {
            own.length = None;
        }
        if lacks(Part::Checksum) {
            own.checksum = None;
        }
        if lacks(Part::End) {
            own.end = None;
        }
        // A part per direction (`covers_from: {request, response}`): each direction's own,
        // its errors located at the direction's key.
        let by_direction = match own.checksum.as_mut() {
            Some(c) => match c.covers_from {
                Some(parts @ model::CoversFrom::ByDirection(_)) => {
                    c.covers_from = Some(model::CoversFrom::Same(parts.of(name == "request")));
                    true
                }
                _ => false,
            },
            None => false,
        };
        let mut errors = Sink::default();
        out.push(framing_plain(&own, byte_order, refs, &mut errors));
        for e in errors.items {
            let path = match e.path.strip_prefix("framing.layout") {
                Some(rest) => format!("framing.layout.{name}{rest}"),
                None if by_direction && e.path == "framing.checksum.covers_from" => {
                    format!("framing.checksum.covers_from.{name}")
                }
                None if header_by_direction
                    && (e.path == "framing.header" || e.path.starts_with("framing.header.")) =>
                {
                    format!("framing.header.{name}{}", &e.path["framing.header".len()..])
                }
                None => e.path,
            };
            if !sink
                .items
                .iter()
                .any(|x| x.path == path && x.message == e.message)
            {
                sink.error(path, e.message);
            }
        }
    }
    let response = out.pop().expect("two framings");
    let mut framing = out.pop().expect("two framings");
    // Each direction's checksum covers from its own first covered byte (a checksum computed
    // on the escaped bytes, which takes one `covers_from`, comes only with escaping by
    // insertion: refused above).
    framing.checksum.response_covers_from = response.checksum.covers_from;
    // Start bytes in one direction's layout only are refused above, as such.
    if let (Some(rq), Some(rs)) = (framing.heads[0].start, response.heads[0].start) {
        if rq != rs {
            sink.error(
                "framing.layout.response",
                format!(
                    "the start bytes sit at offset {rq} in requests and {rs} in responses: {}",
                    not_yet("start bytes at another offset in each direction")
                ),
            );
        }
    }
    if !framing.layout.contains(&Part::Address) {
        framing.address = response.address;
        if framing.address.broadcast.is_some() {
            sink.error(
                "framing.address.broadcast",
                "requests carry no address (their layout has no `address`): none is a broadcast",
            );
        }
    }
    // Each direction's header fields: with one list, the list of both (a direction whose
    // layout has no `header` carries none all the same: `Framing::has_header`).
    let by_direction = matches!(f.header, Some(model::Header::ByDirection(_)));
    if framing.header.is_empty() && !by_direction {
        framing.header = response.header.clone();
    }
    framing.response_header = if by_direction || !response.header.is_empty() {
        response.header
    } else {
        framing.header.clone()
    };
    framing.response_layout = response.layout;
    framing.response_heads = response.heads;
    // Each direction's own end and start bytes (none in a response without them).
    framing.response_end = response.end;
    if bare_responses {
        framing.response_sync = Vec::new();
        // Every start and end byte of a request travels escaped, so that none appears
        // inside a response (stuffed from its first byte to its last) or a request.
        if let Some(Escaping {
            kind: EscapeKind::Bytes { map, .. },
            ..
        }) = &framing.escaping
        {
            let escaped = |b: &u8| map.iter().any(|(r, _)| r == b);
            if let Some(b) = framing
                .sync
                .iter()
                .chain(&framing.end)
                .find(|b| !escaped(b))
            {
                sink.error(
                    "framing.escaping",
                    format!("responses have no start or end bytes (their layout has neither): the requests' start and end bytes travel escaped so that none appears inside a response, and 0x{b:02X} does not"),
                );
            }
        }
    }
    framing
}

fn framing_plain(
    f: &model::Framing,
    byte_order: ByteOrder,
    refs: &Refs,
    sink: &mut Sink,
) -> Framing {
    let path = "framing";
    let count = |p: Part| f.layout.iter().filter(|x| **x == p).count();
    for (p, name) in [(Part::Code, "code"), (Part::Payload, "payload")] {
        if count(p) != 1 {
            sink.error(
                "framing.layout",
                format!("layout must hold `{name}` exactly once, found {}", count(p)),
            );
        }
    }
    // A second `start` repeats the start bytes, a second `length` the length field (M-Bus's
    // long frame `68 L L 68`): both before the payload, and not a third.
    let payload_at = f.layout.iter().position(|p| *p == Part::Payload);
    for (part, name) in [(Part::Start, "start"), (Part::Length, "length")] {
        if count(part) > 2 {
            sink.error(
                "framing.layout",
                format!("layout holds `{name}` more than twice"),
            );
        } else if count(part) == 2 {
            let last = f.layout.iter().rposition(|p| *p == part);
            if last > payload_at {
                sink.error(
                    "framing.layout",
                    format!("a second `{name}` must come before the payload"),
                );
            }
            if f.escaping.is_some() {
                sink.error(
                    "framing.layout",
                    format!("a second `{name}` is not expressible with `escaping` yet"),
                );
            }
        }
    }
    if count(Part::Address) > 1 {
        sink.error("framing.layout", "layout holds `address` more than once");
    }
    if count(Part::End) > 1 {
        sink.error("framing.layout", "layout holds `end` more than once");
    }
    if count(Part::Checksum) > 1 {
        sink.error("framing.layout", "layout holds `checksum` more than once");
    }
    let length = match (count(Part::Length), &f.length) {
        (1.., Some(l)) => {
            let lpath = "framing.length";
            if !(1..=2).contains(&l.width) {
                sink.error(
                    join(lpath, "width"),
                    format!("a length field is 1 or 2 bytes, not {}", l.width),
                );
            }
            if l.counts.is_empty() {
                sink.error(join(lpath, "counts"), "say which parts the length counts");
            } else if !l.counts.contains(&Part::Payload) {
                // A count without the payload is one number whatever the frame holds: the
                // frame's length does not follow from it, which stream framing relies on.
                sink.error(
                    join(lpath, "counts"),
                    "a length field counts the payload (a number that does not is a constant field of the payload)",
                );
            }
            for (i, part) in l.counts.iter().enumerate() {
                if l.counts[..i].contains(part) {
                    sink.error(
                        join(lpath, "counts"),
                        format!("`{}` listed twice", part_name(*part)),
                    );
                }
                if !f.layout.contains(part) {
                    sink.error(
                        join(lpath, "counts"),
                        format!(
                            "counts `{}`, which the layout does not have",
                            part_name(*part)
                        ),
                    );
                }
            }
            // With a long form (`long:`), the IR lays frames out in its width.
            let width = l.long.as_ref().map_or(l.width, |g| g.width.max(l.width));
            Some(LengthField {
                width: width.clamp(1, 2) as usize,
                counts: l.counts.clone(),
                adjust: l.adjust.unwrap_or(0),
            })
        }
        (1.., None) => {
            sink.error(
                "framing.length",
                "layout has `length` but no `length` field is described",
            );
            None
        }
        (_, Some(_)) => {
            sink.error(
                "framing.length",
                "a length field is described but the layout has no `length`",
            );
            None
        }
        _ => None,
    };
    // The frame ends in its checksum and end bytes, in either order: each is last, or just
    // before the other.
    let n = f.layout.len();
    let tail = |p: Part, other: Part| {
        let at = f.layout.iter().position(|x| *x == p);
        at.map_or(true, |at| {
            at + 1 == n || (at + 2 == n && f.layout[n - 1] == other)
        })
    };
    // Or the checksum comes before the payload, covering from a part after it to the
    // frame's end (Septentrio SBF): see `checksum_lead`.
    let pos = |p: Part| f.layout.iter().position(|x| *x == p);
    let lead = matches!((pos(Part::Checksum), pos(Part::Payload)), (Some(c), Some(p)) if c < p);
    if !tail(Part::End, Part::Checksum) {
        sink.error(
            "framing.layout",
            "`end` must be the last part of the frame, or come just before the checksum",
        );
    } else if !lead && !tail(Part::Checksum, Part::End) {
        sink.error(
            "framing.layout",
            "the checksum must be the last part of the frame, or come just before `end`: it covers every byte before it",
        );
    }
    let end = match (count(Part::End), &f.end) {
        (1, Some(e)) => {
            let bytes = e.bytes();
            if !(1..=4).contains(&bytes.len()) {
                sink.error(
                    "framing.end",
                    format!("end bytes are 1 to 4 bytes, found {}", bytes.len()),
                );
            }
            bytes
                .iter()
                .map(|&b| u8_of(b, "framing.end", "end byte", sink))
                .collect()
        }
        (1, None) => {
            sink.error("framing.end", "layout has `end` but no end byte is given");
            Vec::new()
        }
        (_, Some(_)) => {
            sink.error(
                "framing.end",
                "an end byte is given but the layout has no `end`",
            );
            Vec::new()
        }
        _ => Vec::new(),
    };
    let mut sync = Vec::new();
    let mut response_sync = Vec::new();
    let start = match (count(Part::Start), &f.start) {
        (1.., Some(s)) => {
            let sequence = |s: &model::StartBytes, path: &str, sink: &mut Sink| -> Vec<u8> {
                let bytes = s.bytes();
                if !(1..=4).contains(&bytes.len()) {
                    sink.error(
                        path,
                        format!("a sync sequence is 1 to 4 bytes, found {}", bytes.len()),
                    );
                }
                bytes
                    .iter()
                    .map(|&b| u8_of(b, path, "start byte", sink))
                    .collect()
            };
            match s {
                model::Start::Same(s) => {
                    sync = sequence(s, "framing.start", sink);
                    response_sync = sync.clone();
                }
                model::Start::ByDirection(d) => {
                    sync = sequence(&d.request, "framing.start.request", sink);
                    response_sync = sequence(&d.response, "framing.start.response", sink);
                    if sync.len() != response_sync.len() {
                        sink.error(
                            "framing.start",
                            format!(
                                "the start bytes of both directions must be as many (every offset after them is shared), found {} for requests and {} for responses",
                                sync.len(),
                                response_sync.len()
                            ),
                        );
                    } else if sync == response_sync && !sync.is_empty() {
                        sink.error(
                            "framing.start",
                            "the start bytes of both directions are the same: give them once (`start: [...]`)",
                        );
                    }
                    if f.escaping.is_some() {
                        sink.error(
                            "framing.start",
                            "start bytes that differ by direction are not expressible with `escaping` yet",
                        );
                    }
                }
            }
            sync.first().copied()
        }
        (1.., None) => {
            sink.error(
                "framing.start",
                "layout has `start` but no start byte is given",
            );
            None
        }
        (_, Some(_)) => {
            sink.error(
                "framing.start",
                "a start byte is given but the layout has no `start`",
            );
            None
        }
        _ => None,
    };
    let apath = join(path, "address");
    let a = match (count(Part::Address), &f.address) {
        (0, None) => {
            // Frames carry no address: the one device is 0, which no frame shows.
            &model::Address {
                host: None,
                devices: model::Range { min: 0, max: 0 },
                broadcast: None,
                default: None,
            }
        }
        (0, Some(a)) => {
            sink.error(
                apath.clone(),
                "addresses are described but the layout has no `address`",
            );
            a
        }
        (_, Some(a)) => a,
        (_, None) => {
            sink.error(
                apath.clone(),
                "layout has `address` but no `address` section describes the device addresses",
            );
            &model::Address {
                host: None,
                devices: model::Range { min: 0, max: 0 },
                broadcast: None,
                default: None,
            }
        }
    };
    let min = u8_of(a.devices.min, &join(&apath, "devices.min"), "address", sink);
    let max = u8_of(a.devices.max, &join(&apath, "devices.max"), "address", sink);
    if min > max {
        sink.error(
            join(&apath, "devices"),
            format!("device address range is empty: min 0x{min:02X} > max 0x{max:02X}"),
        );
    }
    let host = a
        .host
        .map(|h| u8_of(h, &join(&apath, "host"), "host address", sink));
    let broadcast = a
        .broadcast
        .map(|b| u8_of(b, &join(&apath, "broadcast"), "broadcast address", sink));
    let default = a
        .default
        .map(|d| u8_of(d, &join(&apath, "default"), "default address", sink));
    for (name, v) in [("host", host), ("broadcast", broadcast)] {
        if let Some(v) = v {
            if (min..=max).contains(&v) {
                sink.error(join(&apath, name), format!("{name} address 0x{v:02X} lies inside the device range 0x{min:02X}..=0x{max:02X}"));
            }
        }
    }
    if let Some(d) = default {
        if !(min..=max).contains(&d) {
            sink.error(join(&apath, "default"), format!("default address 0x{d:02X} is outside the device range 0x{min:02X}..=0x{max:02X}"));
        }
    }
    let direction = |d: &model::DirectionFraming, name: &str, sink: &mut Sink| {
        let dpath = join(path, name);
        if d.code_lengths.is_empty() {
            sink.error(
                join(&dpath, "code_lengths"),
                "at least one code length is needed",
            );
        }
        let mut lens = Vec::new();
        for &l in &d.code_lengths {
            if !(0..=4).contains(&l) {
                sink.error(
                    join(&dpath, "code_lengths"),
                    format!("code length {l} is outside 0..=4 bytes"),
                );
            } else {
                lens.push(l as usize);
            }
        }
        // A one-byte length field (without a long form) holds at most 255, so its frames carry
        // at most 255 payload bytes. A two-byte length field or a long length form
        // (`framing.length.long`) carries up to `MAX_LONG_PAYLOAD`; so does a frame without a
        // length field (ended by end bytes, escaping, COBS, or its lists' counts): nothing on
        // the wire caps it, and this bound is what keeps every decoder's buffer finite.
        let one_byte = f
            .length
            .as_ref()
            .is_some_and(|l| l.long.is_none() && l.width != 2);
        let most = if one_byte { 255 } else { MAX_LONG_PAYLOAD };
        if d.payload.min < 0 || d.payload.max < d.payload.min || d.payload.max > most {
            let why = if one_byte {
                "; a one-byte length field counts at most 255 bytes, a two-byte one or a long form (`framing.length.long`) up to 4096"
            } else if f.length.is_none() {
                "; a frame without a length field is bounded by this range, and every decoder's buffer by it"
            } else {
                ""
            };
            sink.error(
                join(&dpath, "payload"),
                format!(
                    "payload length range {}..={} is invalid (0 <= min <= max <= {most}{why})",
                    d.payload.min, d.payload.max
                ),
            );
        }
        DirectionFraming {
            code_lengths: lens,
            payload_min: d.payload.min.clamp(0, most) as usize,
            payload_max: d.payload.max.clamp(0, most) as usize,
        }
    };
    let request = direction(&f.request, "request", sink);
    let response = direction(&f.response, "response", sink);
    let pos = |p: Part| f.layout.iter().position(|x| *x == p);
    if pos(Part::Code) < pos(Part::Address) {
        let lens = all_code_lengths(&request.code_lengths, &response.code_lengths);
        if lens.len() > 1 {
            sink.error(
                "framing.layout",
                format!(
                    "the code comes before the address, so every code must have one length (the address's offset depends on it); code_lengths give {lens:?}"
                ),
            );
        }
    }
    // A length field sits at one offset and holds one rule per direction: where a direction's
    // codes had several lengths, the field after the code would move and one that counts the
    // code would hold another constant per code (`ir::Framing::length_rule`).
    if f.length.is_some() {
        for (name, d) in [("request", &request), ("response", &response)] {
            if d.code_lengths.len() > 1 {
                sink.error(
                    format!("framing.{name}.code_lengths"),
                    format!(
                        "a frame with a length field has codes of one length per direction; code_lengths give {:?}",
                        d.code_lengths
                    ),
                );
            }
        }
    }
    let checksum = match (count(Part::Checksum), &f.checksum) {
        (0, None) => Checksum::none(byte_order),
        (0, Some(c)) => {
            sink.error(
                "framing.checksum",
                "a checksum is described but the layout has no `checksum`",
            );
            checksum_params(c, byte_order, sink)
        }
        (_, Some(c)) => checksum_params(c, byte_order, sink),
        (_, None) => {
            sink.error(
                "framing.checksum",
                "layout has `checksum` but no `checksum` section describes it",
            );
            Checksum::none(byte_order)
        }
    };
    let mut framing = Framing {
        section: f.section.clone(),
        layout: f.layout.to_vec(),
        response_layout: f.layout.to_vec(),
        start,
        sync,
        response_sync,
        response_end: end.clone(),
        end,
        length,
        address: Address {
            host,
            min,
            max,
            broadcast,
            default,
        },
        request,
        response,
        checksum,
        heads: Vec::new(),
        response_heads: Vec::new(),
        escaping: None,
        header: header_fields(f, byte_order, refs, sink),
        response_header: Vec::new(),
        preamble: None,
        transform: None,
        long: None,
        form: None,
        truncation: None,
    };
    framing.heads = (0..=MAX_CODE_LEN)
        .map(|l| frame_layout(&framing, Direction::Request, l, 0))
        .collect();
    framing.response_heads = framing.heads.clone();
    framing.response_header = framing.header.clone();
    if let Some(e) = &f.escaping {
        framing.escaping = escaping(e, &framing, sink);
    }
    if let Some(pre) = &f.preamble {
        framing.preamble = preamble(pre, &framing, sink);
    }
    if let Some(t) = &f.transform {
        framing.transform = transform(t, &framing, sink);
    }
    // A second start or length after the code sits after as many bytes as the code has: one
    // offset only where every code has one length.
    let lens = all_code_lengths(
        &framing.request.code_lengths,
        &framing.response.code_lengths,
    );
    {
        let code_at = f.layout.iter().position(|x| *x == Part::Code);
        for (part, name) in [(Part::Start, "start"), (Part::Length, "length")] {
            let second = f.layout.iter().rposition(|x| *x == part);
            let twice = f.layout.iter().filter(|x| **x == part).count() == 2;
            if twice && second > code_at && lens.len() > 1 {
                sink.error(
                    "framing.layout",
                    format!(
                        "a second `{name}` after the code needs every code to have one length, not {lens:?}: the code's length would move it"
                    ),
                );
            }
        }
    }
    let covers_from = match f.checksum.as_ref().and_then(|c| c.covers_from) {
        Some(model::CoversFrom::ByDirection(_)) => {
            sink.error(
                "framing.checksum.covers_from",
                "a part per direction (`{request: ..., response: ...}`) needs a layout per direction (`framing.layout: {request: [...], response: [...]}`): with one layout, name one part",
            );
            None
        }
        Some(model::CoversFrom::Same(part)) => Some(part),
        None => None,
    };
    if let Some(part) = covers_from {
        // A part after the code sits after as many bytes as the code has: one offset only
        // where every code has one length.
        let pos = |p: Part| f.layout.iter().position(|x| *x == p);
        if pos(Part::Code) < pos(part) && lens.len() > 1 {
            sink.error(
                "framing.checksum.covers_from",
                format!(
                    "the checksum cannot cover from `{}`: it comes after the code, whose lengths {lens:?} would move it",
                    part_name(part)
                ),
            );
        }
        let head = framing.head(Direction::Request, lens.first().copied().unwrap_or(0));
        let at = match part {
            Part::Start => head.start,
            Part::Address => head.address,
            Part::Length => head.length,
            Part::Code => Some(head.code),
            Part::Header => Some(head.headers[0]),
            Part::Payload | Part::Checksum | Part::End => None,
        };
        match at {
            Some(at) if f.layout.contains(&part) => {
                // Both directions' (a layout per direction joins each direction's own).
                framing.checksum.covers_from = at;
                framing.checksum.response_covers_from = at;
            }
            _ => sink.error(
                "framing.checksum.covers_from",
                format!("the checksum cannot cover from `{}`: name a part of the layout before the payload", part_name(part)),
            ),
        }
    }
    if let Some(l) = f.length.as_ref().filter(|l| l.long.is_some()) {
        framing.long = long_form(f, l, &framing, sink);
    }
    if !f.forms.is_empty() {
        framing.form = short_form(f, &framing, byte_order, sink);
    }
    if let Some(t) = f.truncation {
        framing.truncation = truncation(t, f, &framing, sink);
    }
    if lead {
        framing.checksum.lead = checksum_lead(f, &framing, &lens, sink);
    }
    framing
}

/// Where a checksum the layout places before the payload sits (Septentrio SBF's CRC at offset
/// 2, after `$@`, over the ID, length and body after it): it covers from `covers_from`, a part
/// after it, to the frame's end, or a part before it (HerkuleX's size byte): from there to the
/// frame's end, skipping its own bytes. Refused (located): no `covers_from`, one before it
/// under an algorithm other than a sum or XOR ([`splits`]), a code before it of several lengths (it
/// would move), and beside what no engine carries with it yet.
fn checksum_lead(
    f: &model::Framing,
    framing: &Framing,
    lens: &[usize],
    sink: &mut Sink,
) -> Option<usize> {
    let errors = sink.items.len();
    let pos = |p: Part| f.layout.iter().position(|x| *x == p);
    let at_checksum = pos(Part::Checksum)?;
    if pos(Part::Code) < Some(at_checksum) && lens.len() > 1 {
        sink.error(
            "framing.layout",
            format!(
                "the checksum before the payload comes after the code, whose lengths {lens:?} would move it: not expressible yet"
            ),
        );
    }
    match f.checksum.as_ref().and_then(|c| c.covers_from.as_ref()) {
        None => sink.error(
            "framing.checksum.covers_from",
            "the checksum comes before the payload and covers from a part after it to the frame's end: say which (`covers_from`)",
        ),
        Some(model::CoversFrom::Same(part)) => {
            // Bytes on both sides of it (HerkuleX's, from the size byte): a sum or XOR, which
            // generated code takes over two spans without copying them.
            if pos(*part).is_some_and(|p| p < at_checksum) && !splits(&framing.checksum.algorithm)
            {
                sink.error(
                    "framing.checksum.covers_from",
                    format!(
                        "the checksum covers from `{}`, before it, to the frame's end, skipping itself: over two spans only a sum or XOR (sum8, xor8, sum16, their inverted or negated forms, lrc; masked, or followed by its complement) is expressible yet, not {}",
                        part_name(*part),
                        framing.checksum.algorithm.name()
                    ),
                );
            }
        }
        Some(model::CoversFrom::ByDirection(_)) => {}
    }
    let times = |p: Part| f.layout.iter().filter(|x| **x == p).count();
    for (given, what) in [
        (times(Part::End) > 0, "end bytes"),
        (f.escaping.is_some(), "escaping"),
        (f.transform.is_some(), "a transform (`framing.transform`)"),
        (
            f.length.as_ref().is_some_and(|l| l.long.is_some()),
            "a long length form (`framing.length.long`)",
        ),
        (!f.forms.is_empty(), "a short form (`framing.forms`)"),
        (f.truncation.is_some(), "payload truncation"),
        (
            framing.checksum.extra.is_some(),
            "an extra checksum byte per message",
        ),
        (f.preamble.is_some(), "a preamble (`framing.preamble`)"),
    ] {
        if given {
            sink.error(
                "framing.layout",
                format!("a checksum before the payload is not expressible beside {what} yet"),
            );
        }
    }
    if sink.items.len() != errors {
        return None;
    }
    let code_len = lens.first().copied().unwrap_or(0);
    let at = framing
        .part_lens_of(Direction::Request, code_len, 0)
        .take(at_checksum)
        .map(|(_, n)| n)
        .sum();
    Some(at)
}

/// Whether a checksum is taken over two spans as over their bytes in one: a sum or XOR whose
/// value over both is its values over each added (XORed), then inverted or negated, masked or
/// complemented. Not FrSky's end-around sum, Fletcher's running sums, nor a CRC.
pub(crate) fn splits(a: &ChecksumAlgorithm) -> bool {
    match a {
        ChecksumAlgorithm::Sum8
        | ChecksumAlgorithm::Sum8OnesComplement
        | ChecksumAlgorithm::Sum8TwosComplement
        | ChecksumAlgorithm::Xor8
        | ChecksumAlgorithm::Sum16
        | ChecksumAlgorithm::Sum16OnesComplement
        | ChecksumAlgorithm::Sum16TwosComplement => true,
        ChecksumAlgorithm::Masked(inner, _) | ChecksumAlgorithm::Complemented(inner, _) => {
            splits(inner)
        }
        _ => false,
    }
}

/// `framing.truncation`, checked against the rest of the framing (resolved but for it): a
/// length field, once, that counts the payload (it is how the payload's length is found);
/// every code of one length, at least a byte (it is how the message, and so the whole
/// payload's length, is found); no escaping, preamble, transform, end bytes, second start,
/// long length form or short form (not expressible yet).
fn truncation(
    t: model::Truncation,
    spec: &model::Framing,
    f: &Framing,
    sink: &mut Sink,
) -> Option<model::Truncation> {
    let path = "framing.truncation";
    let errors_before = sink.items.len();
    let times = |p: Part| spec.layout.iter().filter(|x| **x == p).count();
    match &f.length {
        None => sink.error(
            path,
            "payload truncation needs a length field (framing.length): it is how a receiver knows how much of the payload came",
        ),
        Some(l) if !l.counts.contains(&Part::Payload) => sink.error(
            path,
            "payload truncation needs a length field that counts the payload",
        ),
        Some(_) if times(Part::Length) > 1 => sink.error(
            path,
            "payload truncation beside a length field sent twice is not expressible yet",
        ),
        Some(_) => {}
    }
    let lens = all_code_lengths(&f.request.code_lengths, &f.response.code_lengths);
    if lens.len() != 1 || lens[0] == 0 {
        sink.error(
            path,
            format!(
                "payload truncation needs every code of one length, at least a byte (the code says which message's payload to pad to), not {lens:?}"
            ),
        );
    }
    for (what, present) in [
        ("escaping", f.escaping.is_some()),
        ("a preamble (framing.preamble)", f.preamble.is_some()),
        ("a transform (framing.transform)", f.transform.is_some()),
        ("end bytes", !f.end.is_empty()),
        ("a second start", times(Part::Start) > 1),
        (
            "a long length form (framing.length.long)",
            f.long.is_some() || l_has_long(spec),
        ),
        ("a frame form (framing.forms)", !spec.forms.is_empty()),
    ] {
        if present {
            sink.error(
                path,
                format!("payload truncation beside {what} is not expressible yet"),
            );
        }
    }
    (errors_before == sink.items.len()).then_some(t)
}

/// Payload truncation (`framing.truncation`) beside the messages: each of a fixed length (no
/// list, no optional field: a padded payload must have one length), every message of one
/// code (either direction) of one payload length, no constant whole frame. Located at the
/// message.
fn truncated_messages(framing: &Framing, msgs: &[Message], list: &str, sink: &mut Sink) {
    if framing.truncation.is_none() {
        return;
    }
    for (i, m) in msgs.iter().enumerate() {
        let path = format!("{list}.{}", m.name);
        if m.frame.is_some() {
            sink.error(
                join(&path, "frame"),
                "a constant whole frame beside payload truncation (framing.truncation) is not expressible yet",
            );
            continue;
        }
        if m.is_variable() || m.has_optional() {
            sink.error(
                &path,
                "beside payload truncation (framing.truncation) every message has one length: lists and optional fields are not expressible yet (a padded payload must have one length)",
            );
        }
        if m.code_from_request.is_some() {
            sink.error(
                &path,
                "a code from the request beside payload truncation (framing.truncation) is not expressible yet",
            );
        }
        if let Some(other) = msgs[..i]
            .iter()
            .find(|o| o.frame.is_none() && o.code == m.code && o.payload_len != m.payload_len)
        {
            sink.error(
                &path,
                format!(
                    "beside payload truncation (framing.truncation) the messages of one code have one payload length (the code says how far to pad): `{}` has {} bytes, this {}",
                    other.name, other.payload_len, m.payload_len
                ),
            );
        }
    }
}

/// [`truncated_messages`] across directions: a request and a response of one code have one
/// payload length (a frame is padded before its direction is known).
fn truncated_across(
    framing: &Framing,
    commands: &[Message],
    responses: &[Message],
    sink: &mut Sink,
) {
    if framing.truncation.is_none() {
        return;
    }
    for r in responses.iter().filter(|r| r.frame.is_none()) {
        if let Some(c) = commands
            .iter()
            .find(|c| c.code == r.code && c.payload_len != r.payload_len)
        {
            sink.error(
                format!("responses.{}", r.name),
                format!(
                    "beside payload truncation (framing.truncation) a request and a response of one code have one payload length (a frame is padded before its direction is known): command `{}` has {} bytes, this {}",
                    c.name, c.payload_len, r.payload_len
                ),
            );
        }
    }
}

/// `framing.forms`, checked against the rest of the framing (resolved but for it): one form,
/// a start byte of its own beside the framing's one start byte, dropping the length field's
/// copies and perhaps the second start, which sit together in the layout after the first start
/// byte (anywhere before the payload); a length that counts the payload, one code length the same both ways, a checksum that
/// covers none of the dropped parts; no long length form, escaping, preamble, transform or
/// header fields beside it (not expressible yet).
fn short_form(
    spec: &model::Framing,
    f: &Framing,
    byte_order: ByteOrder,
    sink: &mut Sink,
) -> Option<ShortForm> {
    let path = "framing.forms";
    let errors_before = sink.items.len();
    if spec.forms.len() > 1 {
        sink.error(
            path,
            format!(
                "one short form beside the layout's own is expressible yet, not {}",
                spec.forms.len()
            ),
        );
    }
    let form = spec.forms.first()?;
    let fpath = format!("{path}[0]");
    let start = u8_of(
        form.start,
        &join(&fpath, "start"),
        "a form's start byte",
        sink,
    );
    let long_start = match (f.sync.as_slice(), spec.start.is_some()) {
        ([b], true) if f.response_sync == f.sync => Some(*b),
        (_, false) => {
            sink.error(
                path,
                "a frame form needs a start byte (`start`): its own start byte tells the forms apart",
            );
            None
        }
        _ => {
            sink.error(
                path,
                "a frame form needs one start byte, the same both ways (not a start sequence or start bytes by direction), yet",
            );
            None
        }
    };
    if long_start == Some(start) {
        sink.error(
            join(&fpath, "start"),
            format!("the form's start byte 0x{start:02X} is the layout's own: the forms need start bytes of their own"),
        );
    }
    let dpath = join(&fpath, "drops");
    let mut drops: Vec<Part> = Vec::new();
    for p in &form.drops {
        if !matches!(p, Part::Length | Part::Start) {
            sink.error(
                &dpath,
                format!(
                    "a form drops `length` and perhaps the second `start`, not `{}`",
                    part_name(*p)
                ),
            );
        } else if drops.contains(p) {
            sink.error(&dpath, format!("`{}` dropped twice", part_name(*p)));
        } else {
            drops.push(*p);
        }
    }
    if !drops.contains(&Part::Length) {
        sink.error(
            &dpath,
            "a form drops the length field (`length`): a short frame is one with an empty payload",
        );
    }
    let Some(l) = &f.length else {
        sink.error(
            path,
            "a frame form needs a length field (`length`) in the layout: the short form drops it",
        );
        return None;
    };
    let (rq, rs) = (&f.request.code_lengths, &f.response.code_lengths);
    if rq.len() != 1 || rq != rs {
        sink.error(
            path,
            "a frame form needs one code length, the same both ways (`code_lengths`), yet: a short frame has one length",
        );
    }
    let head = f.head(Direction::Request, rq.first().copied().unwrap_or(0));
    let start_at = head.start.unwrap_or(0);
    // The dropped parts: every copy of the length field, and the second start bytes.
    let mut runs: Vec<(usize, usize)> = head.lengths().map(|at| (at, l.width)).collect();
    if drops.contains(&Part::Start) {
        match head.start_again {
            Some(at) => runs.push((at, f.sync.len())),
            None => sink.error(
                &dpath,
                "the form drops `start`, but the layout holds the start byte once: only a second `start` can be dropped",
            ),
        }
    } else if head.start_again.is_some() {
        sink.error(
            &dpath,
            "the layout's second `start` stays in the short form: drop it too (`drops: [length, start]`), as the length before it goes",
        );
    }
    runs.sort_unstable();
    let at = runs.first().map_or(0, |r| r.0);
    let together = runs.windows(2).all(|w| w[0].0 + w[0].1 == w[1].0);
    if !together || at <= start_at {
        sink.error(
            "framing.layout",
            "a frame form drops parts that sit together after the first start byte (`start, length, length, start, ...`, `start, code, length, ...`), yet",
        );
    }
    let n: usize = runs.iter().map(|r| r.1).sum();
    if !f.checksum.is_empty() && f.checksum.covers_from < at + n {
        sink.error(
            "framing.checksum",
            "beside a frame form (framing.forms), the checksum covers neither the start byte nor the parts the form drops (`covers_from` a part after them), yet",
        );
    }
    for (what, there) in [
        (
            "a long length form (framing.length.long)",
            f.long.is_some() || l_has_long(spec),
        ),
        ("escaping", f.escaping.is_some()),
        ("preamble", f.preamble.is_some()),
        ("transform", f.transform.is_some()),
        ("header fields (framing.header)", !f.header.is_empty()),
    ] {
        if there {
            sink.error(
                path,
                format!("a frame form (framing.forms) beside {what} is not expressible yet"),
            );
        }
    }
    if errors_before != sink.items.len() {
        return None;
    }
    // The dropped parts' bytes in a frame with an empty payload, as the layout holds them.
    let laid_len = head.len;
    let most = f.length_value(l, rq[0], 0);
    let mut frame = vec![0u8; laid_len];
    for at in head.lengths() {
        crate::interp::write_uint(most as u64, &mut frame[at..at + l.width], byte_order);
    }
    if let Some(again) = head.start_again {
        frame[again..again + f.sync.len()].copy_from_slice(&f.sync);
    }
    Some(ShortForm {
        start,
        long_start: long_start.unwrap_or(0),
        start_at,
        at,
        fill: frame[at..at + n].to_vec(),
        length_at: head.length.unwrap_or(at),
        width: l.width,
        most,
        laid_len,
        drops,
        section: form.section.clone(),
    })
}

/// Whether the spec declares a long length form.
fn l_has_long(spec: &model::Framing) -> bool {
    spec.length.as_ref().is_some_and(|l| l.long.is_some())
}

/// The longest payload of any framing: one with a two-byte length field, a long length form
/// (`framing.length.long`), or no length field (ended by end bytes, escaping, COBS, or its
/// lists' counts). A one-byte length field caps its payloads at 255.
pub const MAX_LONG_PAYLOAD: i64 = 4096;

/// The most preamble bytes a spec may send or accept.
pub const MAX_PREAMBLE: i64 = 16;

/// `framing.preamble`, checked against the rest of the framing (resolved but for it and
/// escaping): a byte, 0 to `max` sent, 1 to [`MAX_PREAMBLE`] accepted; frames that begin with
/// start bytes, the first of which (either direction's) is not the preamble byte; no escaping
/// (not expressible yet).
fn preamble(pre: &model::Preamble, f: &Framing, sink: &mut Sink) -> Option<Preamble> {
    let path = "framing.preamble";
    let errors_before = sink.items.len();
    let byte = u8_of(pre.byte, &join(path, "byte"), "preamble byte", sink);
    let max = pre.max.unwrap_or(pre.send);
    if !(0..=MAX_PREAMBLE).contains(&pre.send) {
        sink.error(
            join(path, "send"),
            format!(
                "a preamble sends 0 to {MAX_PREAMBLE} bytes, not {}",
                pre.send
            ),
        );
    } else if !(1..=MAX_PREAMBLE).contains(&max) {
        sink.error(
            join(path, if pre.max.is_some() { "max" } else { "send" }),
            format!("a preamble accepts 1 to {MAX_PREAMBLE} bytes, not {max}"),
        );
    } else if pre.send > max {
        sink.error(
            join(path, "max"),
            format!(
                "a preamble cannot send more bytes than it accepts: send {} > max {max}",
                pre.send
            ),
        );
    }
    if f.layout.first() != Some(&Part::Start) || f.sync.is_empty() {
        sink.error(
            path,
            "a preamble needs frames that begin with start bytes (framing.start first in the layout): without them a preamble byte could begin a frame",
        );
    } else if f.sync[0] == byte || f.response_sync.first() == Some(&byte) {
        sink.error(
            join(path, "byte"),
            format!("the preamble byte 0x{byte:02X} is a start byte of the framing: a frame's start could not be told from its preamble"),
        );
    }
    if f.escaping.is_some() {
        sink.error(path, "a preamble is not expressible with `escaping`, yet");
    }
    (errors_before == sink.items.len()).then(|| Preamble {
        section: pre.section.clone(),
        byte,
        send: pre.send as u8,
        max: max as u8,
    })
}

/// `framing.transform`, checked against the rest of the framing (resolved but for it):
/// exactly one of `add` and `xor`, a byte other than 0 (which would change nothing); every code
/// of one length (the payload begins at one offset); no escaping (not expressible yet).
fn transform(t: &model::Transform, f: &Framing, sink: &mut Sink) -> Option<Transform> {
    let path = "framing.transform";
    let errors_before = sink.items.len();
    let kind = match (t.add, t.xor) {
        (Some(v), None) => {
            TransformKind::Add(u8_of(v, &join(path, "add"), "a transform's addend", sink))
        }
        (None, Some(v)) => {
            TransformKind::Xor(u8_of(v, &join(path, "xor"), "a transform's XOR mask", sink))
        }
        (Some(_), Some(_)) => {
            sink.error(
                path,
                "a transform either adds (`add`) or XORs (`xor`) a byte, not both",
            );
            return None;
        }
        (None, None) => {
            sink.error(path, "a transform needs `add` or `xor` (the byte every payload byte travels plus, or XOR)");
            return None;
        }
    };
    if errors_before == sink.items.len() {
        if let (TransformKind::Add(0), key) | (TransformKind::Xor(0), key) =
            (kind, if t.add.is_some() { "add" } else { "xor" })
        {
            sink.error(
                join(path, key),
                format!(
                    "a transform with `{key}: 0` changes no byte: leave `framing.transform` out"
                ),
            );
        }
    }
    let lens = all_code_lengths(&f.request.code_lengths, &f.response.code_lengths);
    if lens.len() > 1 {
        sink.error(
            path,
            format!(
                "a transform needs every code of one length (the payload at one offset), not {}, yet",
                lens.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(" and ")
            ),
        );
    }
    if f.escaping.is_some() {
        sink.error(path, "a transform is not expressible with `escaping`, yet");
    }
    (errors_before == sink.items.len()).then(|| Transform {
        section: t.section.clone(),
        kind,
    })
}

/// `framing.length.long`, checked against the rest of the framing (resolved but for it; its
/// length field already as wide as the long form): a wider long form, at most 2 bytes, a start
/// byte of its own; a one-byte start (the same both ways) and the length field right after it
/// (the only part before the length field is the start byte, so every other part sits one
/// width later in the long form); a checksum that covers neither and a length that counts
/// neither (so both are the same in either form); no escaping, preamble or transform, nor a
/// second start or length, nor examples printed in another byte order (not expressible yet).
fn long_form(
    spec: &model::Framing,
    l: &model::LengthField,
    f: &Framing,
    sink: &mut Sink,
) -> Option<LongForm> {
    let long = l.long.as_ref()?;
    let path = "framing.length.long";
    let errors_before = sink.items.len();
    let start = u8_of(
        long.start,
        &join(path, "start"),
        "the long form's start byte",
        sink,
    );
    if long.width <= l.width || long.width > 2 {
        sink.error(
            join(path, "width"),
            format!(
                "the long form's length field is wider than the short one's {} byte(s) and at most 2 bytes, not {}",
                l.width, long.width
            ),
        );
    }
    let short_start = match (f.sync.as_slice(), spec.start.is_some()) {
        ([b], true) if f.response_sync == f.sync => Some(*b),
        (_, false) => {
            sink.error(
                path,
                "a long form needs a start byte (`start`): its own start byte tells the forms apart",
            );
            None
        }
        _ => {
            sink.error(
                path,
                "a long form needs one start byte, the same both ways (not a start sequence or start bytes by direction), yet",
            );
            None
        }
    };
    if short_start == Some(start) {
        sink.error(
            join(path, "start"),
            format!("the long form's start byte 0x{start:02X} is the short form's: the forms need start bytes of their own"),
        );
    }
    if !matches!(spec.layout.as_slice(), [Part::Start, Part::Length, ..]) {
        sink.error(
            "framing.layout",
            "a long length form (framing.length.long) needs the layout to begin with `start, length`",
        );
    }
    let twice = |p: Part| spec.layout.iter().filter(|x| **x == p).count() > 1;
    if twice(Part::Start) || twice(Part::Length) {
        sink.error(
            "framing.layout",
            "a second `start` or `length` beside a long length form (framing.length.long) is not expressible yet",
        );
    }
    for (part, name) in [(Part::Start, "start"), (Part::Length, "length")] {
        if l.counts.contains(&part) {
            sink.error(
                "framing.length.counts",
                format!("beside a long form (`long`), the length counts no `{name}`: it differs by form"),
            );
        }
    }
    let head = f.head(Direction::Request, 0);
    let (start_at, length_at) = (head.start.unwrap_or(0), head.length.unwrap_or(1));
    if !f.checksum.is_empty()
        && f.checksum.covers_from < length_at + f.length.as_ref().map_or(0, |l| l.width)
    {
        sink.error(
            "framing.checksum",
            "beside a long length form (framing.length.long), the checksum covers neither the start byte nor the length field (`covers_from` a part after them), yet",
        );
    }
    for (what, there) in [
        ("escaping", f.escaping.is_some()),
        ("preamble", f.preamble.is_some()),
        ("transform", f.transform.is_some()),
    ] {
        if there {
            sink.error(
                path,
                format!("a long length form beside `{what}` is not expressible yet"),
            );
        }
    }
    (errors_before == sink.items.len()).then(|| LongForm {
        start,
        short_start: short_start.unwrap_or(0),
        short_width: l.width as usize,
        width: long.width as usize,
        start_at,
        length_at,
    })
}

/// A transform (`framing.transform`) beside a list whose count field a stream would read
/// before the frame's length is known (no length field): not expressible yet, located at the
/// list.
/// Text up to a terminator without a length field ([`Message::terminated_text`]): a stream
/// decoder frames it by reading for its terminator, one variable-length message for the
/// bytes its code and leading constants agree with, so no other variable-length message of
/// its direction may share its code (a message without a code shares every code).
fn terminated_apart(framing: &Framing, msgs: &[Message], list: &str, sink: &mut Sink) {
    for m in msgs {
        let Some((f, _, _)) = m.terminated_text(framing) else {
            continue;
        };
        let shares = |o: &&Message| {
            o.name != m.name
                && o.frame.is_none()
                && o.is_variable()
                && (o.code.starts_with(&m.code) || m.code.starts_with(&o.code))
        };
        if let Some(o) = msgs.iter().find(shares) {
            sink.error(
                format!("{list}.{}.fields.{}.repeat.until", m.name, f.name),
                format!("text up to a terminator without a length field (framing.length) beside `{}`, a variable-length message its code does not tell apart, is not expressible yet: a stream decoder frames one variable-length message per code", o.name),
            );
        }
    }
}

fn transform_lists(framing: &Framing, msgs: &[Message], list: &str, sink: &mut Sink) {
    if framing.transform.is_none() || framing.length.is_some() {
        return;
    }
    for m in msgs {
        for (_, f, r) in m.repeats() {
            if matches!(r.count, Count::Elements(_) | Count::Bytes(_)) {
                sink.error(
                    format!("{list}.{}.fields.{}", m.name, f.name),
                    "a list counted by a field beside a transform (framing.transform) needs a length field (framing.length), yet",
                );
            }
        }
        // Its end bytes would be looked for among the payload's bytes as they travel.
        if let Some((f, _)) = m.delimited_list(framing) {
            sink.error(
                format!("{list}.{}.fields.{}", m.name, f.name),
                "a list to the end of a frame that end bytes alone delimit (no length field, no checksum) beside a transform (framing.transform) is not expressible yet",
            );
        }
    }
}

/// `framing.escaping`, checked against the rest of the framing (resolved but for it).
fn escaping(e: &model::Escaping, f: &Framing, sink: &mut Sink) -> Option<Escaping> {
    let path = "framing.escaping";
    let errors_before = sink.items.len();
    let byte =
        |v: i64, key: &str, what: &str, sink: &mut Sink| u8_of(v, &join(path, key), what, sink);
    let kinds = [e.escape.is_some(), e.insert.is_some(), e.cobs.is_some()];
    if kinds.iter().filter(|k| **k).count() != 1 {
        sink.error(
            path,
            "give exactly one kind: `escape` (SLIP, KISS, HDLC), `insert` (Dynamixel 2.0) or `cobs`",
        );
        return None;
    }
    let misplaced = |keys: &[(&str, bool)], kind: &str, sink: &mut Sink| {
        for (key, given) in keys {
            if *given {
                sink.error(
                    join(path, key),
                    format!("`{key}` does not belong to `{kind}`"),
                );
            }
        }
    };
    let last_is_end = f.layout.last() == Some(&Part::End);
    let start_first = !f.layout.contains(&Part::Start) || f.layout.first() == Some(&Part::Start);
    let kind = if let Some(esc) = e.escape {
        misplaced(
            &[("after", e.after.is_some()), ("from", e.from.is_some())],
            "escape",
            sink,
        );
        let escape = byte(esc, "escape", "escape byte", sink);
        let map: Vec<(u8, u8)> = match (&e.bytes, e.xor, &e.map) {
            (Some(bytes), Some(mask), None) => {
                let mask = byte(mask, "xor", "mask", sink);
                if mask == 0 {
                    sink.error(join(path, "xor"), "a mask of 0 leaves every byte as it is");
                }
                bytes
                    .iter()
                    .map(|&b| {
                        let b = byte(b, "bytes", "escaped byte", sink);
                        (b, b ^ mask)
                    })
                    .collect()
            }
            (None, None, Some(map)) => map
                .iter()
                .map(|m| {
                    (
                        byte(m.byte, "map", "escaped byte", sink),
                        byte(m.replacement, "map", "replacement", sink),
                    )
                })
                .collect(),
            _ => {
                sink.error(
                    path,
                    "`escape` takes `xor` with `bytes`, or `map` alone: how each escaped byte travels",
                );
                Vec::new()
            }
        };
        let key = if e.map.is_some() { "map" } else { "bytes" };
        if map.is_empty() && errors_before == sink.items.len() {
            sink.error(join(path, key), "list the bytes that travel escaped");
        }
        for (i, (raw, rep)) in map.iter().enumerate() {
            if map[..i].iter().any(|(r, _)| r == raw) {
                sink.error(join(path, key), format!("0x{raw:02X} listed twice"));
            }
            if map[..i].iter().any(|(_, r)| r == rep) {
                sink.error(
                    join(path, key),
                    format!("two bytes travel as 0x{escape:02X} 0x{rep:02X}"),
                );
            }
            // The escape byte escaping itself: it travels doubled (Garmin's DLE stuffing).
            let doubled = *raw == escape && *rep == escape;
            if !doubled && map.iter().any(|(r, _)| r == rep) {
                sink.error(
                    join(path, key),
                    format!("0x{raw:02X} travels as 0x{rep:02X}, a byte that is itself escaped"),
                );
            }
        }
        if !map.is_empty() && !map.iter().any(|(r, _)| *r == escape) {
            sink.error(
                join(path, "escape"),
                format!("the escape byte 0x{escape:02X} must itself travel escaped: list it"),
            );
        }
        // Framed by an end byte (SLIP, KISS, HDLC), or without one by the length field
        // (XBee API mode 2), which then sits at one offset, read as the bytes unescape; or,
        // where the escape byte travels doubled, by the escape byte and a byte that follows
        // it nowhere else (Garmin's DLE ETX, found by pairing).
        let doubled = map.iter().any(|&(r, s)| r == escape && s == escape);
        let by_end = last_is_end
            && ((f.end.len() == 1 && map.iter().any(|(r, _)| Some(r) == f.end.first()))
                || (doubled && f.end.len() == 2 && f.end[0] == escape));
        if doubled && last_is_end && f.end.len() == 2 && f.end[0] == escape {
            let after = f.end[1];
            if after == escape {
                sink.error(
                    "framing.end",
                    format!("0x{escape:02X} 0x{after:02X} is a doubled escape byte, not an end: the byte after the escape byte that ends a frame must stand for no byte"),
                );
            } else if let Some((raw, _)) = map.iter().find(|(_, r)| *r == after) {
                sink.error(
                    "framing.end",
                    format!("0x{escape:02X} 0x{after:02X} also stands for 0x{raw:02X} inside a frame: the byte after the escape byte that ends a frame must be no replacement"),
                );
            }
        }
        if doubled && !(last_is_end && f.end.len() == 2 && f.end[0] == escape) {
            sink.error(
                join(path, key),
                format!("0x{escape:02X} travels doubled (0x{escape:02X} 0x{escape:02X}): frames then end in two `end` bytes, the escape byte and a byte no escape stands for (Garmin's DLE ETX: `end: [0x10, 0x03]`, the last part of the layout)"),
            );
        }
        let codes = f
            .request
            .code_lengths
            .iter()
            .map(|&c| (Direction::Request, c))
            .chain(
                f.response
                    .code_lengths
                    .iter()
                    .map(|&c| (Direction::Response, c)),
            );
        let length_at: Vec<Option<usize>> = codes.map(|(d, c)| f.head(d, c).length).collect();
        let by_length = !f.layout.contains(&Part::End)
            && f.length.is_some()
            && length_at
                .first()
                .is_some_and(|first| first.is_some() && length_at.iter().all(|at| at == first));
        if !by_end && !by_length && !doubled {
            sink.error(
                path,
                "escaped frames end in one `end` byte (the last part of the layout) that travels escaped inside them, or in the escape byte and another where it travels doubled (`{byte: 0x10, as: 0x10}`, `end: [0x10, 0x03]`), or, without `end`, carry a length field at one offset (before the code, or every code one length): it is how a frame's end is found",
            );
        }
        EscapeKind::Bytes {
            escape,
            map,
            xor: e.xor.map(|m| m.clamp(0, 255) as u8),
        }
    } else if let Some(ins) = e.insert {
        misplaced(
            &[
                ("xor", e.xor.is_some()),
                ("bytes", e.bytes.is_some()),
                ("map", e.map.is_some()),
            ],
            "insert",
            sink,
        );
        let inserted = byte(ins, "insert", "inserted byte", sink);
        let after: Vec<u8> = match &e.after {
            Some(a) => a
                .bytes()
                .iter()
                .map(|&b| byte(b, "after", "pattern byte", sink))
                .collect(),
            None => {
                sink.error(join(path, "after"), "say after which bytes `insert` goes");
                Vec::new()
            }
        };
        if !(1..=4).contains(&after.len()) && e.after.is_some() {
            sink.error(
                join(path, "after"),
                format!("a pattern is 1 to 4 bytes, found {}", after.len()),
            );
        }
        let from = e.from.unwrap_or(Part::Code);
        let pos = |p: Part| f.layout.iter().position(|x| *x == p);
        let (pf, pc, pl) = (pos(from), pos(Part::Code), pos(Part::Length));
        let ok = matches!(from, Part::Address | Part::Code)
            && pf.is_some()
            && pf <= pc
            && pl.is_some_and(|l| Some(l) < pf);
        if !ok {
            sink.error(
                join(path, "from"),
                format!(
                    "stuffing from `{}`: name the address or the code, after the length field (stuffing runs from it through the payload)",
                    part_name(from)
                ),
            );
        }
        if e.computed != Computed::Escaped {
            sink.error(
                join(path, "computed"),
                "stuffed frames are framed by their length field: it and the checksum count the stuffed bytes (`computed: escaped`, as Dynamixel 2.0)",
            );
        }
        if let (Some(l), true) = (&f.length, ok) {
            let region = [Part::Address, Part::Code, Part::Payload];
            let stuffed = region
                .iter()
                .filter(|p| pos(**p) >= pf && pos(**p).is_some());
            if let Some(p) = stuffed.clone().find(|p| !l.counts.contains(p)) {
                sink.error(
                    "framing.length.counts",
                    format!(
                        "the length field counts the stuffed bytes: it must count `{}`",
                        part_name(*p)
                    ),
                );
            }
        }
        EscapeKind::Insert {
            after,
            byte: inserted,
            from,
        }
    } else {
        misplaced(
            &[
                ("xor", e.xor.is_some()),
                ("bytes", e.bytes.is_some()),
                ("map", e.map.is_some()),
                ("after", e.after.is_some()),
                ("from", e.from.is_some()),
            ],
            "cobs",
            sink,
        );
        if e.cobs == Some(false) {
            sink.error(
                join(path, "cobs"),
                "`cobs: false` is no escaping: leave `escaping` out",
            );
        }
        if !last_is_end || f.end != [0] {
            sink.error(
                path,
                "COBS frames end in the end byte 0x00 (`end: 0x00`, the last part of the layout)",
            );
        }
        EscapeKind::Cobs
    };
    if !matches!(kind, EscapeKind::Insert { .. }) {
        if !start_first {
            sink.error(
                "framing.layout",
                "with escaping, `start` is the first part of the layout: the escaped bytes lie between it and `end`",
            );
        }
        if e.computed != Computed::Unescaped {
            sink.error(
                join(path, "computed"),
                "the checksum and length travel escaped themselves: they are computed on the frame before escaping (`computed: unescaped`)",
            );
        }
    }
    let escaping = Escaping {
        section: e.section.clone(),
        computed: e.computed,
        kind,
    };
    // The longest frame stuffed must still fit its length field.
    if let (Some(l), EscapeKind::Insert { .. }) = (&f.length, &escaping.kind) {
        let longest = (f
            .request
            .code_lengths
            .iter()
            .map(|&c| (Direction::Request, c, f.request.payload_max)))
        .chain(
            f.response
                .code_lengths
                .iter()
                .map(|&c| (Direction::Response, c, f.response.payload_max)),
        )
        .map(|(d, c, pl)| f.head(d, c).len + pl)
        .max()
        .unwrap_or(0);
        let probe = Framing {
            escaping: Some(escaping.clone()),
            ..f.clone()
        };
        let most = probe.wire_len(longest) as i64 + l.adjust;
        let limit = (1i64 << (8 * l.width)) - 1;
        if most > limit {
            sink.error(
                "framing.length.width",
                format!("the longest frame stuffed takes {most} bytes, more than a {}-byte length field holds", l.width),
            );
        }
    }
    (errors_before == sink.items.len()).then_some(escaping)
}

/// `framing.header`: the fields every message carries, each an integer of 1 to 4 bytes with
/// its unit, range, enum or flags; `offset` counted from the layout's `header` part.
fn header_fields(
    f: &model::Framing,
    byte_order: ByteOrder,
    refs: &Refs,
    sink: &mut Sink,
) -> Vec<Field> {
    use model::FieldType as T;
    let in_layout = f.layout.iter().filter(|p| **p == Part::Header).count();
    let fields = match &f.header {
        Some(model::Header::Same(fields)) => fields,
        Some(model::Header::ByDirection(_)) => {
            sink.error(
                "framing.header",
                "header fields per direction (`{request: [...], response: [...]}`) need a layout per direction (`framing.layout: {request: [...], response: [...]}`): with one layout, give one list",
            );
            return Vec::new();
        }
        None => {
            if in_layout > 0 {
                sink.error(
                    "framing.layout",
                    "layout has `header` but `framing.header` is missing",
                );
            }
            return Vec::new();
        }
    };
    let path = "framing.header";
    if in_layout == 0 {
        sink.error(
            path,
            "`framing.header` needs a `header` part in the layout, where its fields sit",
        );
    }
    if in_layout > MAX_HEADER_PARTS {
        sink.error(
            "framing.layout",
            format!("layout holds `header` {in_layout} times: at most {MAX_HEADER_PARTS}"),
        );
    }
    if f.layout
        .windows(2)
        .any(|w| w == [Part::Header, Part::Header])
    {
        sink.error(
            "framing.layout",
            "two `header` parts side by side: one `header` holds all their fields",
        );
    }
    let pos = |p: Part| f.layout.iter().position(|x| *x == p);
    let last_header = f.layout.iter().rposition(|x| *x == Part::Header);
    if in_layout > 0 && last_header > pos(Part::Payload) {
        sink.error("framing.layout", "`header` must come before the payload");
    }
    if in_layout > 0 && last_header > pos(Part::Code) && {
        let mut lens: Vec<i64> = f
            .request
            .code_lengths
            .iter()
            .chain(&f.response.code_lengths)
            .copied()
            .collect();
        lens.sort_unstable();
        lens.dedup();
        lens.len() > 1
    } {
        sink.error(
            "framing.layout",
            "a `header` after the code needs every code to have one length: the code's length would move it",
        );
    }
    if fields.is_empty() {
        sink.error(
            path,
            "`framing.header` is empty: give its fields or leave it out",
        );
    }
    let mut out: Vec<Field> = Vec::new();
    let mut offset = 0;
    // The `header` part each field sits in (`part`, from 1), in layout order.
    let mut part = 0;
    for h in fields {
        let p = join(path, &h.name);
        match h.part {
            None | Some(1) if part == 0 => {}
            None => sink.error(
                join(&p, "part"),
                format!("a field after those of `header` part {} needs its `part`: fields are listed in layout order", part + 1),
            ),
            Some(n) if n < 1 || n > in_layout.max(1) as i64 => sink.error(
                join(&p, "part"),
                if in_layout > 1 {
                    format!("part {n} is not one of the layout's `header` parts, 1 to {in_layout}")
                } else {
                    format!("part {n}: the layout holds `header` once, so every field sits in part 1 (leave `part` out)")
                },
            ),
            Some(n) if ((n - 1) as usize) < part => sink.error(
                join(&p, "part"),
                format!("part {n} after a field of part {}: list the fields in layout order", part + 1),
            ),
            Some(n) => {
                let n = (n - 1) as usize;
                // The first part that could be left without a field.
                let next = if out.is_empty() { 0 } else { part + 1 };
                if n > next {
                    sink.error(
                        join(&p, "part"),
                        format!("`header` part {} holds no field: every `header` of the layout holds at least one", next + 1),
                    );
                }
                if n != part {
                    offset = 0;
                }
                part = n;
            }
        }
        check_ident(&h.name, &p, "field", sink);
        if out.iter().any(|g| g.name == h.name) {
            sink.error(&p, format!("duplicate field name `{}`", h.name));
        }
        if !matches!(
            h.ty,
            T::U8 | T::U16 | T::U24 | T::U32 | T::I8 | T::I16 | T::I24 | T::I32
        ) {
            sink.error(
                join(&p, "type"),
                "a header field is an integer of 1 to 4 bytes (u8 u16 u24 u32 i8 i16 i24 i32)",
            );
            continue;
        }
        if refuse_keys(
            h,
            &p,
            &[
                "equals",
                "repeat",
                "packed",
                "follows",
                "fields",
                "bytes",
                "encoding",
                "word_order",
                "length",
                "present",
            ],
            |k| {
                format!("`{k}` cannot be used in a header field (an integer every message carries, with its unit, range, enum, flags, special values or sub-fields)")
            },
            sink,
        ) {
            continue;
        }
        let mut field = {
            let h = model::Field {
                part: None,
                ..h.clone()
            };
            field(&h, &p, offset, byte_order, &out, refs, sink)
        };
        field.header = true;
        field.part = part;
        for b in &field.bits {
            let taken = out
                .iter()
                .any(|g| g.name == b.name || g.bits.iter().any(|c| c.name == b.name));
            if taken {
                sink.error(
                    join(&join(&p, "bits"), &b.name),
                    format!("duplicate field name `{}`", b.name),
                );
            }
        }
        offset += field.width;
        out.push(field);
    }
    if in_layout > 1 && !out.is_empty() && part + 1 < in_layout {
        sink.error(
            path,
            format!(
                "the layout holds `header` {in_layout} times and the fields fill {}: give each part its fields (`part: N`)",
                part + 1
            ),
        );
    }
    out
}

/// A field that refers to a header field (of the first `headers` of the message): by counting
/// it, repeating it, following it or taking its bytes from it.
fn header_reference(f: &Field, headers: usize) -> Option<usize> {
    let count = f.repeat.as_ref().and_then(|r| r.count.field());
    let follows = match f.follows {
        Some(Follows::Field(i, _)) => Some(i),
        _ => None,
    };
    let bytes = f.record.iter().find_map(|g| g.bytes_from);
    [count, f.equals, follows, bytes]
        .into_iter()
        .flatten()
        .find(|&i| i < headers)
}

/// Where each part of a frame sits when its code has `code_len` bytes and its payload
/// `payload_len`. Used only here, while the IR is built; everything else reads the result from
/// [`Message::layout`] and [`Framing::head`].
fn frame_layout(
    framing: &Framing,
    d: Direction,
    code_len: usize,
    payload_len: usize,
) -> FrameLayout {
    let mut o = FrameLayout {
        start: None,
        start_again: None,
        length: None,
        length_again: None,
        address: None,
        headers: [0; MAX_HEADER_PARTS],
        code: 0,
        payload: 0,
        checksum: 0,
        len: 0,
    };
    let mut at = 0;
    let mut headers = 0;
    for part in framing.layout_of(d) {
        match part {
            Part::Start => {
                match o.start {
                    None => o.start = Some(at),
                    Some(_) => o.start_again = Some(at),
                }
                at += framing.sync.len();
            }
            Part::Length => {
                match o.length {
                    None => o.length = Some(at),
                    Some(_) => o.length_again = Some(at),
                }
                at += framing.length.as_ref().map_or(0, |l| l.width);
            }
            Part::Address => {
                o.address = Some(at);
                at += 1;
            }
            Part::Code => {
                o.code = at;
                at += code_len;
            }
            Part::Payload => {
                o.payload = at;
                at += payload_len;
                // Where the checksum is, or would be: the payload's end (a layout without a
                // checksum keeps this).
                o.checksum = at;
            }
            Part::Checksum => {
                o.checksum = at;
                at += framing.checksum.len();
            }
            Part::End => at += framing.end.len(),
            Part::Header => {
                // Parts past the most are refused (`header_fields`).
                if let Some(h) = o.headers.get_mut(headers) {
                    *h = at;
                }
                at += framing.header_part_len_of(d, headers);
                headers += 1;
            }
        }
    }
    o.len = at;
    o
}

fn checksum_params(c: &model::Checksum, byte_order: ByteOrder, sink: &mut Sink) -> Checksum {
    let path = "framing.checksum";
    // Errors found elsewhere before this point must not hide a wrong check value.
    let errors_before = sink.items.len();
    // 24 bits: a CRC's (RTCM 3's CRC-24Q); every sum has a width of its own, checked below.
    let width = if matches!(c.width, 8 | 16 | 24 | 32) {
        c.width as u8
    } else {
        sink.error(
            join(path, "width"),
            format!("checksum width {} is not 8, 16, 24 or 32 bits", c.width),
        );
        8
    };
    let fits = |v: i64, key: &str, sink: &mut Sink| -> u64 {
        if fits_unsigned(v, u32::from(width)) {
            v as u64
        } else {
            sink.error(
                join(path, key),
                format!("{key} {} does not fit in {width} bits", hex_or_negative(v)),
            );
            0
        }
    };
    let crc_keys = [
        ("poly", c.poly.is_some()),
        ("init", c.init.is_some()),
        ("refin", c.refin.is_some()),
        ("refout", c.refout.is_some()),
        ("xorout", c.xorout.is_some()),
    ];
    use model::ChecksumAlgorithm as A;
    let algorithm = match c.algorithm {
        A::Sum8
        | A::Sum8OnesComplement
        | A::Sum8TwosComplement
        | A::Sum8EndAround
        | A::Lrc
        | A::Xor8
        | A::Sum16
        | A::Sum16OnesComplement
        | A::Sum16TwosComplement
        | A::Fletcher8
        | A::Fletcher16 => {
            let (name, bits, algorithm) = match c.algorithm {
                A::Sum8OnesComplement => (
                    "sum8_ones_complement",
                    8,
                    ChecksumAlgorithm::Sum8OnesComplement,
                ),
                A::Sum8TwosComplement => (
                    "sum8_twos_complement",
                    8,
                    ChecksumAlgorithm::Sum8TwosComplement,
                ),
                A::Sum8EndAround => ("sum8_end_around", 8, ChecksumAlgorithm::Sum8EndAround),
                A::Lrc => ("lrc", 8, ChecksumAlgorithm::Sum8TwosComplement),
                A::Xor8 => ("xor8", 8, ChecksumAlgorithm::Xor8),
                A::Sum16 => ("sum16", 16, ChecksumAlgorithm::Sum16),
                A::Sum16OnesComplement => (
                    "sum16_ones_complement",
                    16,
                    ChecksumAlgorithm::Sum16OnesComplement,
                ),
                A::Sum16TwosComplement => (
                    "sum16_twos_complement",
                    16,
                    ChecksumAlgorithm::Sum16TwosComplement,
                ),
                A::Fletcher8 => ("fletcher8", 16, ChecksumAlgorithm::Fletcher8),
                A::Fletcher16 => ("fletcher16", 16, ChecksumAlgorithm::Fletcher16),
                _ => ("sum8", 8, ChecksumAlgorithm::Sum8),
            };
            if width != bits {
                sink.error(join(path, "width"), format!("{name} is {bits} bits wide"));
            }
            for (k, given) in crc_keys {
                if given {
                    sink.error(
                        join(path, k),
                        format!("`{k}` is a CRC parameter; {name} takes none"),
                    );
                }
            }
            algorithm
        }
        model::ChecksumAlgorithm::Crc => {
            for (k, given) in crc_keys {
                if !given {
                    sink.error(join(path, k), format!("a CRC needs `{k}`"));
                }
            }
            let poly = fits(c.poly.unwrap_or(1), "poly", sink);
            if poly & 1 == 0 {
                sink.error(
                    join(path, "poly"),
                    format!(
                        "poly 0x{poly:X} is even: a CRC generator polynomial has its x^0 term set"
                    ),
                );
            }
            ChecksumAlgorithm::Crc(CrcParams {
                width,
                poly,
                init: fits(c.init.unwrap_or(0), "init", sink),
                refin: c.refin.unwrap_or(false),
                refout: c.refout.unwrap_or(false),
                xorout: fits(c.xorout.unwrap_or(0), "xorout", sink),
            })
        }
    };
    let algorithm = match c.mask {
        None => algorithm,
        Some(m) => {
            let sum = matches!(
                algorithm,
                ChecksumAlgorithm::Sum8
                    | ChecksumAlgorithm::Sum8OnesComplement
                    | ChecksumAlgorithm::Sum8TwosComplement
                    | ChecksumAlgorithm::Sum8EndAround
                    | ChecksumAlgorithm::Xor8
                    | ChecksumAlgorithm::Sum16
                    | ChecksumAlgorithm::Sum16OnesComplement
                    | ChecksumAlgorithm::Sum16TwosComplement
            );
            if !sum {
                sink.error(
                    join(path, "mask"),
                    "a mask keeps some bits of a sum or XOR (sum8, sum8_ones_complement, sum8_twos_complement, sum8_end_around, lrc, xor8, sum16, sum16_ones_complement, sum16_twos_complement), not of this algorithm",
                );
            }
            let mask = fits(m, "mask", sink);
            if mask == 0 {
                sink.error(join(path, "mask"), "a mask of 0 keeps no bit");
            }
            ChecksumAlgorithm::Masked(Box::new(algorithm), mask)
        }
    };
    let check = fits(c.check, "check", sink);
    let computed = checksum::compute(&algorithm, checksum::CHECK_INPUT);
    let digits = usize::from(width / 4);
    if sink.items.len() == errors_before && computed != check {
        sink.error(
            join(path, "check"),
            format!("check value 0x{check:0digits$X} does not match the parameters, which give 0x{computed:0digits$X} over \"123456789\""),
        );
    }
    if width > 8 && c.byte_order.is_none() {
        sink.error(
            join(path, "byte_order"),
            "a multi-byte checksum must say its byte order",
        );
    }
    // Followed by its complement (HerkuleX's CS1, CS2): two bytes, the value first.
    let (algorithm, width, byte_order) = match c.complement {
        Some(true) => {
            let (inner, mask) = match &algorithm {
                ChecksumAlgorithm::Masked(inner, m) => (&**inner, *m),
                a => (a, 0xFF),
            };
            let eight = matches!(
                inner,
                ChecksumAlgorithm::Sum8
                    | ChecksumAlgorithm::Sum8OnesComplement
                    | ChecksumAlgorithm::Sum8TwosComplement
                    | ChecksumAlgorithm::Sum8EndAround
                    | ChecksumAlgorithm::Xor8
            );
            if !eight || width != 8 {
                sink.error(
                    join(path, "complement"),
                    "a complement byte follows an 8-bit sum or XOR (sum8, sum8_ones_complement, sum8_twos_complement, sum8_end_around, lrc, xor8; width 8), not this checksum",
                );
            } else if c.byte_order.is_some() {
                sink.error(
                    join(path, "byte_order"),
                    "a checksum followed by its complement sends its value first: it takes no byte order",
                );
            }
            (
                ChecksumAlgorithm::Complemented(Box::new(algorithm), mask),
                16,
                ByteOrder::Big,
            )
        }
        _ => (algorithm, width, c.byte_order.unwrap_or(byte_order)),
    };
    Checksum {
        algorithm,
        width,
        byte_order,
        catalogue: c.catalogue.clone(),
        check,
        covers_from: 0,
        response_covers_from: 0,
        extra: None,
        lead: None,
    }
}

struct Refs<'a> {
    units: &'a Names,
    enums: &'a Names,
    flags: &'a Names,
    enum_defs: &'a [Enum],
    flag_defs: &'a [FlagSet],
    unit_defs: &'a [Unit],
}

/// Parses `"0x2000"`: the number of hex digits gives the code's width.
fn parse_code(code: &str, path: &str, sink: &mut Sink) -> Option<Vec<u8>> {
    if code.is_empty() {
        // No code: the frame's kind is told by its length and its request alone.
        return Some(Vec::new());
    }
    let digits = code.strip_prefix("0x").or_else(|| code.strip_prefix("0X"));
    let Some(digits) = digits
        .filter(|d| !d.is_empty() && d.len() % 2 == 0 && d.bytes().all(|b| b.is_ascii_hexdigit()))
    else {
        sink.error(path, format!("code `{code}` must be written as 0x followed by an even number of hex digits, e.g. \"0x2000\""));
        return None;
    };
    interp::parse_hex(digits).ok()
}

/// The most repeated fields one message may have (the generated stream decoder reads their
/// count fields into an array of this many).
pub const MAX_LISTS: usize = 64;

/// The most packed elements one field may hold.
pub const MAX_PACKED: i64 = 256;

/// What [`message_body`] resolves: code, fields, fixed payload bytes, most payload bytes.
type Body = (Vec<u8>, Vec<Field>, usize, usize);

/// A response's constant whole frame (`frame:`), its rules checked: hex bytes, 1 to
/// [`MAX_CONSTANT_FRAME`] of them; no code, fields, request-bound keys or checksum byte; a
/// framing whose every frame begins with its start bytes, none of whose first bytes the constant
/// frame begins with (a stream could not tell it from a frame's start otherwise); no escaping
/// or header fields (not expressible yet); not equal to, a prefix of or prefixed by another.
fn constant_frame(
    r: &model::Response,
    text: &str,
    framing: &Framing,
    earlier: &[(&str, Vec<u8>)],
    path: &str,
    sink: &mut Sink,
) -> Vec<u8> {
    let fpath = join(path, "frame");
    let frame = match interp::parse_hex(text) {
        Ok(b) => b,
        Err(_) if text.chars().all(|c| c.is_whitespace() || c == ',') => {
            sink.error(
                &fpath,
                format!("a constant frame is 1 to {MAX_CONSTANT_FRAME} bytes, not 0"),
            );
            return Vec::new();
        }
        Err(e) => {
            sink.error(&fpath, format!("a constant frame is hex bytes: {e}"));
            return Vec::new();
        }
    };
    if frame.len() > MAX_CONSTANT_FRAME {
        sink.error(
            &fpath,
            format!(
                "a constant frame is 1 to {MAX_CONSTANT_FRAME} bytes, not {}",
                frame.len()
            ),
        );
    }
    for (key, given) in [
        ("code", r.code.is_some()),
        ("fields", !r.fields.is_empty()),
        ("needs_request", r.needs_request),
        ("code_from_request", r.code_from_request.is_some()),
        ("checksum_extra", r.checksum_extra.is_some()),
        ("checksum_over_request", r.checksum_over_request.is_some()),
        ("checksum", r.checksum.is_some()),
    ] {
        if given {
            sink.error(
                join(path, key),
                format!("a constant frame (`frame`) is its bytes alone: it takes no `{key}`"),
            );
        }
    }
    let first = frame.first().copied();
    if framing.layout.first() != Some(&Part::Start) || framing.sync.is_empty() {
        sink.error(
            &fpath,
            "a constant frame needs frames that begin with start bytes (framing.start first in the layout): without them any frame could begin with its bytes",
        );
    } else if let Some(b) = first.filter(|b| {
        *b == framing.sync[0]
            || Some(b) == framing.response_sync.first()
            || framing.form.as_ref().is_some_and(|f| f.start == *b)
    }) {
        sink.error(
            &fpath,
            format!("a constant frame cannot begin with 0x{b:02X}, a start byte of the framing: it could not be told from a frame's start"),
        );
    }
    if framing.escaping.is_some() {
        sink.error(
            &fpath,
            "a constant frame is not expressible with `escaping`, yet",
        );
    }
    if framing.preamble.is_some() {
        sink.error(
            &fpath,
            "a constant frame is not expressible with a preamble (framing.preamble), yet",
        );
    }
    if !framing.header.is_empty() || !framing.response_header.is_empty() {
        sink.error(
            &fpath,
            "a constant frame is not expressible with header fields (framing.header), yet: every message carries them",
        );
    }
    for (name, other) in earlier {
        if other.is_empty() || frame.is_empty() {
            continue;
        }
        if *other == frame {
            sink.error(
                &fpath,
                format!("the same constant frame as response `{name}`"),
            );
        } else if other.starts_with(&frame) || frame.starts_with(other) {
            sink.error(
                &fpath,
                format!("constant frame {} and response `{name}`'s {}: one is a prefix of the other, so a stream could not tell where one ends", spaced_hex(&frame), spaced_hex(other)),
            );
        }
    }
    frame
}

/// A message's `header:` values: each names a whole header field of its direction
/// (`framing.header`) and becomes that field's constant in this message's copy of it, which
/// both engines check and write as any constant field's (a frame with another value is not
/// this message). Header constants do not tell messages apart: two messages with one code
/// and length are refused as before (`template` leaves header fields out).
fn header_constants(
    values: &BTreeMap<String, i64>,
    headers: &mut [Field],
    path: &str,
    direction: Direction,
    sink: &mut Sink,
) {
    let hpath = join(path, "header");
    for (name, &v) in values {
        let p = join(&hpath, name);
        let Some(f) = headers.iter_mut().find(|f| &f.name == name) else {
            let sub = headers
                .iter()
                .find(|f| f.bits.iter().any(|b| &b.name == name));
            let why = match sub {
                Some(f) => format!(
                    "`{name}` is a sub-field of header field `{}`: give the whole field's value",
                    f.name
                ),
                None if headers.is_empty() => format!(
                    "{}s carry no header fields (framing.header, with `header` in their layout)",
                    direction.as_str()
                ),
                None => format!(
                    "no header field `{name}` in {}s; they carry {}",
                    direction.as_str(),
                    headers
                        .iter()
                        .map(|f| format!("`{}`", f.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            };
            sink.error(p, why);
            continue;
        };
        if let Some(c) = f.constant {
            sink.error(
                p,
                format!("header field `{name}` is a constant of framing.header ({c:#04X}): every message carries it"),
            );
            continue;
        }
        let bits = 8 * f.width as u32;
        if !fits_unsigned(v, bits) {
            sink.error(
                p,
                format!(
                    "{} does not fit in the {bits}-bit header field `{name}`",
                    hex_or_negative(v)
                ),
            );
            continue;
        }
        if !f.bits.is_empty() {
            sink.error(
                p,
                format!("header field `{name}` has sub-fields (`bits`): a value for the whole of it is not expressible yet"),
            );
            continue;
        }
        f.constant = Some(v as u64);
        let read = f.constant_value().unwrap_or(v);
        if let Some((min, max)) = f.range.filter(|&(lo, hi)| read < lo || read > hi) {
            sink.error(
                p,
                format!(
                    "{} is outside header field `{name}`'s range {min}..={max}",
                    hex_or_negative(v)
                ),
            );
        }
    }
}

/// Bytes as `E5 00`.
fn spaced_hex(bytes: &[u8]) -> String {
    let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
    hex.join(" ")
}

#[allow(clippy::too_many_arguments)]
fn message_body(
    code: Option<&str>,
    fields: &[model::Field],
    header_values: &BTreeMap<String, i64>,
    path: &str,
    direction: Direction,
    framing: &Framing,
    byte_order: ByteOrder,
    refs: &Refs,
    sink: &mut Sink,
) -> Body {
    // No code (a response without one, reported where it is read): none to check either.
    let code = code.and_then(|code| parse_code(code, &join(path, "code"), sink));
    let parsed = code.is_some();
    let code = code.unwrap_or_default();
    let dir = framing.direction(direction);
    if parsed && !dir.code_lengths.contains(&code.len()) {
        sink.error(
            join(path, "code"),
            format!(
                "a {}-byte code, but {}s have codes of {:?} bytes (framing.{}.code_lengths)",
                code.len(),
                direction.as_str(),
                dir.code_lengths,
                direction.as_str()
            ),
        );
    }
    let fpath = join(path, "fields");
    let (fields, fixed): (Vec<model::Field>, Vec<Option<usize>>) = fields
        .iter()
        .map(|f| fixed_list(f, &join(&fpath, &f.name), sink))
        .unzip();
    let fields = fields.as_slice();
    // Field and sub-field names share one name space per message: they are the keys of its values.
    // The header fields' values (each whole, or its sub-fields) are named in every message.
    let headers: &[Field] = if framing.has_header(direction) {
        framing.header_of(direction)
    } else {
        &[]
    };
    let mut leaf_names: BTreeSet<String> = headers
        .iter()
        .flat_map(|h| {
            let own = h.bits.is_empty().then(|| h.name.clone());
            own.into_iter().chain(h.bits.iter().map(|b| b.name.clone()))
        })
        .collect();
    // The header fields every message carries come first (they sit in the frame's header),
    // each with the value this message gives it, if any.
    let mut out: Vec<Field> = headers.to_vec();
    header_constants(header_values, &mut out, path, direction, sink);
    let mut offset = 0usize;
    let mut tail = 0usize;
    let mut min_tail = 0usize;
    let mut optional = 0usize;
    let mut counters = BTreeSet::new();
    for (i, f) in fields.iter().enumerate() {
        let p = join(&fpath, &f.name);
        check_ident(&f.name, &p, "field", sink);
        if let Some(r) = &f.repeat {
            // A list to the end takes what the fields after it leave: none of them may vary.
            if r.count == "end" && fields[i + 1..].iter().any(|g| g.repeat.is_some()) {
                sink.error(
                    join(&join(&p, "repeat"), "count"),
                    "a repeat to the `end` must be the last repeated field (the fields after it must have a fixed size); count this one by an earlier field",
                );
            }
            // A stream without a length field lists a list to the end's lengths beforehand,
            // which another list in the frame would multiply.
            if r.count == "end"
                && framing.length.is_none()
                && fields.iter().filter(|g| g.repeat.is_some()).count() > 1
            {
                sink.error(
                    join(&join(&p, "repeat"), "count"),
                    "a repeat to the `end` beside another repeated field needs a length field (framing.length): without one a stream decoder cannot tell where the frame ends",
                );
            }
        }
        if let Some(r) = f.repeat.as_ref().filter(|r| r.until.is_some()) {
            // Its terminator is found by reading the frame: a stream needs the frame's length
            // first, and the bytes must be the characters as they are.
            // Without a length field the terminator alone ends the frame: the text is the
            // message's only list, the bytes as they travel are its characters.
            let lists = fields.iter().filter(|g| g.repeat.is_some()).count();
            let why = if framing.transform.is_some() {
                Some("text up to a terminator beside a transform (framing.transform) is not expressible yet")
            } else if framing.length.is_none() && framing.escaping.is_some() {
                Some("text up to a terminator without a length field (framing.length) beside escaping (framing.escaping) is not expressible yet")
            } else if framing.length.is_none() && lists > 1 {
                Some("text up to a terminator without a length field (framing.length) must be its message's only repeated field: its terminator alone tells where the frame ends")
            } else {
                None
            };
            if let (Some(why), true) = (why, r.count.is_empty()) {
                sink.error(join(&join(&p, "repeat"), "until"), why);
            }
        }
        if f.bits.is_empty() && !leaf_names.insert(f.name.clone()) {
            let what = if headers
                .iter()
                .any(|h| h.name == f.name || h.bits.iter().any(|b| b.name == f.name))
            {
                " (a header field every message carries: framing.header)"
            } else {
                ""
            };
            sink.error(&p, format!("duplicate field name `{}`{what}", f.name));
        }
        let mut field = field(f, &p, offset, byte_order, &out, refs, sink);
        if let Some(n) = fixed[i] {
            fixed_elements(&mut field, n);
        }
        if let Some(pr) = &f.present {
            field.present = presence(f, pr, &p, &out, fields, sink);
        }
        if let Some(h) = header_reference(&field, headers.len()) {
            sink.error(
                &p,
                format!(
                    "refers to `{}`, a header field (framing.header): a message's counts, copies and relations refer to its payload's fields",
                    out[h].name
                ),
            );
        }
        for b in &field.bits {
            if !leaf_names.insert(b.name.clone()) {
                sink.error(
                    join(&join(&p, "bits"), &b.name),
                    format!("duplicate field name `{}`", b.name),
                );
            }
        }
        if let Some(c) = field.repeat.as_ref().and_then(|r| r.count.field()) {
            if !counters.insert(c) {
                sink.error(
                    join(&join(&p, "repeat"), "count"),
                    format!(
                        "`{}` already counts another repeated field; each list has a count field of its own",
                        out[c].name
                    ),
                );
            }
        }
        match &field.repeat {
            Some(r) => {
                tail += field.elements_len(r.max);
                min_tail += field.elements_len(r.min);
            }
            // An optional field sits after every fixed one, where the optional fields before
            // it leave it (`ir::Field::present`); the frame's shortest length leaves it out.
            None if f.present.is_some() => optional += field.width,
            None => offset += field.width,
        }
        out.push(field);
    }
    optional_layout(fields, &fpath, framing, sink);
    let lists = out.iter().filter(|f| f.repeat.is_some()).count();
    // A record whose width a field gives: the one list, last, framed by a length field (a
    // stream decoder lists no lengths of it beforehand, nor places fields after it).
    if let Some((i, f)) = out
        .iter()
        .enumerate()
        .find(|(_, f)| f.record_bytes_from().is_some())
    {
        let g = f.record.last().map_or("", |g| g.name.as_str());
        let bp = join(&join(&join(&join(&fpath, &f.name), "fields"), g), "bytes");
        if framing.length.is_none() {
            sink.error(
                &bp,
                "a record whose width a field gives needs a length field (framing.length) to frame it",
            );
        } else if lists > 1 || i + 1 != out.len() {
            sink.error(
                &bp,
                "a record whose width a field gives is the message's only repeated field and its last field",
            );
        }
    }
    if lists > MAX_LISTS {
        sink.error(
            &fpath,
            format!("{lists} repeated fields; a message has at most {MAX_LISTS}"),
        );
    }
    if offset + min_tail < dir.payload_min || offset + tail + optional > dir.payload_max {
        let most = if tail > 0 {
            let which = if fields.iter().filter(|f| f.repeat.is_some()).count() > 1 {
                "fields"
            } else {
                "field"
            };
            format!(" (and up to {tail} more in the repeated {which})")
        } else if optional > 0 {
            format!(" (and up to {optional} more in the optional fields)")
        } else {
            String::new()
        };
        sink.error(
            &fpath,
            format!(
                "fields add up to {offset} payload bytes{most}, but {} payloads are {}..={} bytes (framing.{}.payload)",
                direction.as_str(),
                dir.payload_min,
                dir.payload_max,
                direction.as_str()
            ),
        );
    }
    (code, out, offset, offset + tail + optional)
}

/// The most optional fields (`present:`) a message may have.
pub const MAX_OPTIONAL: usize = 4;

/// An optional field's condition (`present: {field, bit | equals}`), resolved against the
/// fields before it (`earlier`, header fields first); and what an optional field may be: a
/// plain number of a fixed width.
fn presence(
    f: &model::Field,
    pr: &model::Present,
    p: &str,
    earlier: &[Field],
    all: &[model::Field],
    sink: &mut Sink,
) -> Option<Presence> {
    use model::FieldType as T;
    let pp = join(p, "present");
    refuse_keys(
        f,
        p,
        &[
            "value", "equals", "follows", "bits", "repeat", "packed", "fields", "encoding",
        ],
        |k| {
            format!("`{k}` cannot be combined with `present`: an optional field is a plain number of a fixed width")
        },
        sink,
    );
    if matches!(f.ty, T::Ascii | T::Bit | T::Record) {
        sink.error(
            join(p, "type"),
            "an optional field (`present`) is a number of a fixed width (u8 to u64, i8 to i64, f32, f64)",
        );
    }
    let fp = join(&pp, "field");
    let Some(i) = earlier.iter().position(|g| g.name == pr.field && !g.header) else {
        let why = if earlier.iter().any(|g| g.name == pr.field) {
            format!("`{}` is a header field (framing.header): a condition reads a field of the message's payload", pr.field)
        } else if all.iter().any(|g| g.name == pr.field) {
            format!(
                "`{}` comes later: a condition reads a field before the optional one",
                pr.field
            )
        } else {
            format!("no field `{}` before this one", pr.field)
        };
        sink.error(fp, why);
        return None;
    };
    let g = &earlier[i];
    let refused = if g.present.is_some() {
        Some("an optional field")
    } else if g.repeat.is_some() || g.packed.is_some() {
        Some("a list")
    } else if g.ty == T::Ascii {
        Some("text")
    } else if g.is_float() {
        Some("a float")
    } else if g.signed {
        Some("signed")
    } else if g.bcd {
        Some("BCD")
    } else if g.word_swapped {
        Some("word-swapped")
    } else if g.equals.is_some() || g.follows.is_some() {
        Some("derived from another field (`equals`, `follows`)")
    } else {
        None
    };
    if let Some(what) = refused {
        sink.error(
            fp,
            format!("`{}` is {what}: a condition reads an unsigned binary integer that is always on the wire", g.name),
        );
        return None;
    }
    let bits = 8 * g.width as u32;
    let when = match (pr.bit, pr.equals) {
        (Some(b), None) => {
            if !(0..i64::from(bits)).contains(&b) {
                sink.error(
                    join(&pp, "bit"),
                    format!("bit {b} is outside `{}`'s bits 0..={}", g.name, bits - 1),
                );
                return None;
            }
            PresentWhen::Bit(b as u32)
        }
        (None, Some(v)) => {
            if v < 0 || !fits_unsigned(v, bits) {
                sink.error(
                    join(&pp, "equals"),
                    format!("{v} does not fit `{}` (0..={})", g.name, g.raw_span().1),
                );
                return None;
            }
            PresentWhen::Equals(v)
        }
        _ => {
            sink.error(
                pp,
                "`present` takes exactly one of `bit` and `equals` beside `field`",
            );
            return None;
        }
    };
    Some(Presence { field: i, when })
}

/// A message with optional fields is the one message of its code (a code of its own, not
/// taken from its request) in a direction where every message has a code: its frames are
/// told apart by the code alone, whatever their length.
fn optional_codes(msgs: &[Message], list: &str, sink: &mut Sink) {
    let codeless = msgs.iter().find(|m| m.code.is_empty() && m.frame.is_none());
    for m in msgs.iter().filter(|m| m.has_optional()) {
        let Some((_, f, _)) = m.optionals().next() else {
            continue;
        };
        let pp = join(
            &join(&join(&join(list, &m.name), "fields"), &f.name),
            "present",
        );
        if m.code.is_empty() {
            sink.error(
                pp,
                "optional fields in a message without a code are not expressible yet",
            );
        } else if m.code_from_request.is_some() {
            sink.error(pp, "optional fields in a message whose code comes from the request are not expressible yet");
        } else if let Some(o) = msgs.iter().find(|o| o.name != m.name && o.code == m.code) {
            sink.error(
                pp,
                format!("optional fields in a message whose code `{}` `{}` shares are not expressible yet", m.code_hex(), o.name),
            );
        } else if let Some(c) = codeless {
            sink.error(
                pp,
                format!("optional fields where a message of the direction has no code (`{}`) are not expressible yet", c.name),
            );
        }
    }
}

/// Where optional fields may stand in a message's fields: last, beside no list, at most
/// [`MAX_OPTIONAL`], in a framing with a length field (which gives each frame's length, so a
/// stream decoder frames it without reading its conditions) and without escaping.
fn optional_layout(fields: &[model::Field], fpath: &str, framing: &Framing, sink: &mut Sink) {
    let Some(first) = fields.iter().position(|f| f.present.is_some()) else {
        return;
    };
    let name = &fields[first].name;
    for f in fields[first + 1..].iter().filter(|f| f.present.is_none()) {
        sink.error(
            join(fpath, &f.name),
            format!(
                "a field after the optional field `{name}`: optional fields end the message, yet"
            ),
        );
    }
    let n = fields.iter().filter(|f| f.present.is_some()).count();
    if n > MAX_OPTIONAL {
        sink.error(
            fpath,
            format!("{n} optional fields; a message has at most {MAX_OPTIONAL}"),
        );
    }
    let pp = join(&join(fpath, name), "present");
    if let Some(l) = fields.iter().find(|f| f.repeat.is_some()) {
        sink.error(
            &pp,
            format!(
                "optional fields beside a repeated field (`{}`) are not expressible yet",
                l.name
            ),
        );
    }
    if framing.length.is_none() {
        sink.error(
            &pp,
            "optional fields need a length field (framing.length): it gives each frame's length, which the fields present must agree with",
        );
    }
    if framing.escaping.is_some() {
        sink.error(
            &pp,
            "optional fields with `escaping` are not expressible yet",
        );
    }
}

fn field(
    f: &model::Field,
    p: &str,
    offset: usize,
    byte_order: ByteOrder,
    earlier: &[Field],
    refs: &Refs,
    sink: &mut Sink,
) -> Field {
    use model::FieldType as T;
    let (width, signed) = match f.ty {
        T::U8 => (1, false),
        T::U16 => (2, false),
        T::U32 => (4, false),
        T::I8 => (1, true),
        T::I16 => (2, true),
        T::I32 => (4, true),
        T::U24 => (3, false),
        T::I24 => (3, true),
        T::U64 => (8, false),
        T::I64 => (8, true),
        T::F32 => (4, false),
        T::F64 => (8, false),
        T::Bit => (1, false),
        // A record's width is its fields' (below).
        T::Record => (1, false),
        // Text a count field counts (`repeat`): a character is one element of one byte.
        T::Ascii if f.repeat.is_some() => {
            if f.length.is_some() {
                sink.error(
                    join(p, "length"),
                    "`length` cannot be combined with `repeat`: the count field gives the text's length, `repeat.max` its most",
                );
            }
            (1, false)
        }
        T::Ascii => match f.length {
            Some(n) if (1..=255).contains(&n) => (n as usize, false),
            Some(n) => {
                sink.error(
                    join(p, "length"),
                    format!("ascii length {n} is outside 1..=255"),
                );
                (1, false)
            }
            None => {
                sink.error(join(p, "length"), "an ascii field needs a `length`");
                (1, false)
            }
        },
    };
    let bits = 8 * width as u32;
    if f.ty != T::Ascii && f.length.is_some() {
        sink.error(
            join(p, "length"),
            "`length` is only for ascii fields; a number's width comes from its type",
        );
    }
    if f.part.is_some() {
        sink.error(
            join(p, "part"),
            "`part` places a header field (framing.header) in one of the layout's `header` parts: other fields sit in the payload",
        );
    }
    let mut out = Field {
        name: f.name.clone(),
        doc: text(&f.doc),
        ty: f.ty,
        offset,
        width,
        signed,
        byte_order,
        word_swapped: f.word_order == Some(model::WordOrder::Swapped),
        bcd: f.encoding == Some(model::Encoding::Bcd),
        unit: None,
        range: None,
        constant: None,
        enumeration: None,
        flags: None,
        equals: None,
        special: Vec::new(),
        bits: Vec::new(),
        repeat: None,
        packed: None,
        follows: None,
        record: Vec::new(),
        bytes_from: None,
        header: false,
        part: 0,
        present: None,
    };
    if f.bytes.is_some() {
        sink.error(
            join(p, "bytes"),
            "`bytes` is only for a record's last field (its bytes given by an earlier field of the message)",
        );
    }
    if f.ty != T::Record && !f.fields.is_empty() {
        sink.error(
            join(p, "fields"),
            "`fields` is only for a `type: record` (a repeated group of fields)",
        );
    }
    if f.ty == T::Record {
        return record_field(f, p, out, byte_order, earlier, refs, sink);
    }
    if f.word_order.is_some()
        && !matches!(f.ty, T::U32 | T::I32 | T::F32 | T::U64 | T::I64 | T::F64)
    {
        sink.error(
            join(p, "word_order"),
            "`word_order` is for 32- and 64-bit numbers (u32 i32 f32 u64 i64 f64), whose 16-bit words it orders",
        );
    }
    if let Some(pk) = &f.packed {
        return packed_field(f, pk, p, out, refs, sink);
    }
    if matches!(f.ty, T::U64 | T::I64 | T::F32 | T::F64) {
        if out.bcd {
            sink.error(
                join(p, "encoding"),
                "`encoding: bcd` is for unsigned fields of 1 to 4 bytes (u8 u16 u24 u32)",
            );
        }
        return wide_field(f, p, out, earlier, refs, sink);
    }
    if out.bcd {
        return bcd_field(f, p, out, refs, sink);
    }
    if let Some(r) = &f.repeat {
        out.repeat = repeat(r, f, &join(p, "repeat"), earlier, sink);
        refuse_keys(
            f,
            p,
            &["value", "equals", "bits", "special", "follows"],
            |k| format!("`{k}` cannot be combined with `repeat`"),
            sink,
        );
    }
    if f.ty == T::Bit {
        if f.repeat.is_none() {
            sink.error(
                join(p, "type"),
                "a `bit` is only the element of a repeated field (coils); give it a `repeat`",
            );
        }
        refuse_keys(
            f,
            p,
            &["unit", "range", "enum", "flags", "follows"],
            |k| format!("`{k}` cannot be combined with a bit"),
            sink,
        );
        return out;
    }
    if let Some(fo) = &f.follows {
        let fpath = join(p, "follows");
        let relation =
            |name: &str, sink: &mut Sink| relation(name, fo.multiply, fo.divide, &fpath, sink);
        match (&fo.field, &fo.request) {
            (Some(other), None) => {
                refuse_keys(f, p, &["unit", "range", "value", "enum", "flags", "equals", "bits", "special"], |k| format!("`{k}` cannot be combined with `follows` a field: its value is computed"), sink);
                match earlier.iter().position(|e| &e.name == other) {
                    Some(i) if earlier[i].bits.is_empty() && !earlier[i].is_ascii() && !earlier[i].is_wide() && !earlier[i].bcd && !earlier[i].is_list() => {
                        out.follows = Some(Follows::Field(i, relation(other, sink)));
                    }
                    Some(_) => sink.error(
                        join(&fpath, "field"),
                        format!("`{other}` is not a plain number field"),
                    ),
                    None => sink.error(
                        join(&fpath, "field"),
                        format!("refers to `{other}`, which is not an earlier field of this message"),
                    ),
                }
                return out;
            }
            (None, Some(other)) => out.follows = Some(Follows::Request(relation(other, sink))),
            _ => sink.error(
                &fpath,
                "give exactly one of `field` (an earlier field of this frame) and `request` (a field of the request)",
            ),
        }
    }
    let given: Vec<&str> = [
        ("unit", f.unit.is_some()),
        ("range", f.range.is_some()),
        ("value", f.value.is_some()),
        ("enum", f.enum_.is_some()),
        ("flags", f.flags.is_some()),
        ("equals", f.equals.is_some()),
        ("special", !f.special.is_empty()),
        ("bits", !f.bits.is_empty()),
    ]
    .into_iter()
    .filter(|(_, g)| *g)
    .map(|(k, _)| k)
    .collect();
    let allow = |allowed: &[&str], what: &str, sink: &mut Sink| {
        for k in &given {
            if !allowed.contains(k) {
                sink.error(join(p, k), format!("`{k}` cannot be combined with {what}"));
            }
        }
    };

    if f.ty == T::Ascii {
        allow(&[], "an ascii field", sink);
        return out;
    }
    if let Some(v) = f.value {
        allow(&["value"], "a constant `value`", sink);
        if fits_unsigned(v, bits) {
            out.constant = Some(v as u64);
        } else {
            sink.error(
                join(p, "value"),
                format!(
                    "constant {} does not fit in a {bits}-bit field",
                    hex_or_negative(v)
                ),
            );
        }
        return out;
    }
    if let Some(other) = &f.equals {
        allow(&["equals"], "`equals`", sink);
        match earlier.iter().position(|e| &e.name == other) {
            Some(i) if earlier[i].is_list() => sink.error(
                join(p, "equals"),
                format!("`{other}` is a repeated field; a field repeats one earlier value"),
            ),
            Some(i) if earlier[i].ty == f.ty => out.equals = Some(i),
            Some(_) => sink.error(join(p, "equals"), format!("`{other}` has a different type")),
            None => sink.error(
                join(p, "equals"),
                format!("refers to `{other}`, which is not an earlier field of this message"),
            ),
        }
        return out;
    }
    if !f.bits.is_empty() {
        allow(&["bits"], "packed `bits`", sink);
        if signed {
            sink.error(
                join(p, "type"),
                "a packed field must have an unsigned type; sub-fields say their own signedness",
            );
        }
        out.bits = bit_fields(&f.bits, bits, p, refs, sink);
        return out;
    }
    if let Some(e) = &f.enum_ {
        allow(&["enum", "range"], "an enum", sink);
        match refs.enums.get(e) {
            Some(i) => {
                out.enumeration = Some(i);
                for v in &refs.enum_defs[i].values {
                    if !fits_unsigned(v.value as i64, bits) {
                        sink.error(
                            join(p, "enum"),
                            format!(
                                "enum `{e}` value {} ({}) does not fit in a {bits}-bit field",
                                v.name, v.value
                            ),
                        );
                    }
                }
            }
            None => sink.error(
                join(p, "enum"),
                format!("refers to enum `{e}`, which is not defined"),
            ),
        }
    } else if let Some(fl) = &f.flags {
        allow(&["flags"], "flags", sink);
        match refs.flags.get(fl) {
            Some(i) => {
                out.flags = Some(i);
                for b in &refs.flag_defs[i].bits {
                    if u32::from(b.bit) >= bits {
                        sink.error(
                            join(p, "flags"),
                            format!(
                                "flag `{}` is bit {}, outside a {bits}-bit field",
                                b.name, b.bit
                            ),
                        );
                    }
                }
            }
            None => sink.error(
                join(p, "flags"),
                format!("refers to flag set `{fl}`, which is not defined"),
            ),
        }
    } else {
        match &f.unit {
            Some(u) => match refs.units.get(u) {
                Some(i) => out.unit = Some(i),
                None => sink.error(
                    join(p, "unit"),
                    format!("refers to unit `{u}`, which is not defined in `units`"),
                ),
            },
            None => sink.error(
                p,
                "a number field needs a `unit` (or an enum, flags, bits, constant value or equals)",
            ),
        }
    }
    out.range = f
        .range
        .and_then(|r| int_range(r, &join(p, "range"), sink))
        .and_then(|r| range(r, bits, signed, &join(p, "range"), sink));
    let mut names = BTreeSet::new();
    for s in &f.special {
        let sp = join(&join(p, "special"), &s.name);
        check_ident(&s.name, &sp, "special value", sink);
        if !names.insert(s.name.clone()) {
            sink.error(&sp, format!("duplicate special value name `{}`", s.name));
        }
        let (min, max) = raw_limits(bits, signed);
        if s.value < min || s.value > max {
            sink.error(
                &sp,
                format!(
                    "special value {} does not fit in the field ({min}..={max})",
                    s.value
                ),
            );
        }
        out.special.push(Special {
            value: s.value,
            name: s.name.clone(),
            doc: text(&s.doc),
        });
    }
    out
}

/// A repeated record (`type: record`): its `repeat`, and its fields, each a fixed-width
/// integer with what a plain number field takes (unit, enum, flags, range, special values),
/// nothing that varies, repeats or derives from another field.
fn record_field(
    f: &model::Field,
    p: &str,
    mut out: Field,
    byte_order: ByteOrder,
    earlier: &[Field],
    refs: &Refs,
    sink: &mut Sink,
) -> Field {
    use model::FieldType as T;
    refuse_keys(
        f,
        p,
        &[
            "length",
            "word_order",
            "unit",
            "range",
            "value",
            "enum",
            "flags",
            "equals",
            "special",
            "bits",
            "follows",
            "present",
        ],
        |k| format!("`{k}` cannot be combined with a record: its fields take their own"),
        sink,
    );
    let fpath = join(p, "fields");
    if f.fields.is_empty() {
        sink.error(&fpath, "a record needs at least one field");
    }
    let mut names = BTreeSet::new();
    let mut offset = 0usize;
    for g in &f.fields {
        let gp = join(&fpath, &g.name);
        check_ident(&g.name, &gp, "field", sink);
        if !names.insert(g.name.clone()) {
            sink.error(
                &gp,
                format!("duplicate field name `{}` in the record", g.name),
            );
        }
        if !matches!(
            g.ty,
            T::U8 | T::U16 | T::U24 | T::U32 | T::I8 | T::I16 | T::I24 | T::I32
        ) {
            sink.error(
                join(&gp, "type"),
                "a record's field is an integer of 8 to 32 bits (u8 u16 u24 u32 i8 i16 i24 i32); records of text, bits, records, floats or 64-bit integers are not expressible yet",
            );
            continue;
        }
        let refused = refuse_keys(
            g,
            &gp,
            &[
                "repeat",
                "value",
                "equals",
                "follows",
                "bits",
                "word_order",
                "fields",
                "packed",
                "encoding",
                "present",
            ],
            |k| {
                format!("`{k}` cannot be used in a record's field (each is a plain number of a fixed width)")
            },
            sink,
        );
        if refused {
            continue;
        }
        let mut plain = g.clone();
        plain.bytes = None;
        let mut sub = field(&plain, &gp, offset, byte_order, &[], refs, sink);
        if let Some(by) = &g.bytes {
            sub.bytes_from = record_bytes(g, by, &gp, f, earlier, sink);
        }
        offset += sub.width;
        out.record.push(sub);
    }
    out.width = offset.max(1);
    match &f.repeat {
        Some(r) => out.repeat = repeat(r, f, &join(p, "repeat"), earlier, sink),
        None => sink.error(
            join(p, "type"),
            "a `record` is only the element of a repeated field; give it a `repeat`",
        ),
    }
    out
}

/// An unsigned plain number field: what counts a list or gives a record's width (no sign,
/// 64-bit or float type, BCD, text, bits or list).
fn plain_unsigned(f: &Field) -> bool {
    !f.signed && !f.is_wide() && !f.bcd && !f.is_ascii() && f.bits.is_empty() && !f.is_list()
}

/// A record's last field whose bytes an earlier field of the message gives (`bytes:
/// data_length`, Dynamixel SYNC_WRITE): that field's index, where it is an unsigned plain
/// number field and the record runs to the end of the frame.
fn record_bytes(
    g: &model::Field,
    by: &str,
    gp: &str,
    f: &model::Field,
    earlier: &[Field],
    sink: &mut Sink,
) -> Option<usize> {
    let path = join(gp, "bytes");
    if f.fields.last().map(|l| l.name.as_str()) != Some(g.name.as_str()) {
        sink.error(
            &path,
            "only a record's last field takes its bytes from another field (the fields after it would move)",
        );
        return None;
    }
    if f.repeat.as_ref().is_some_and(|r| r.request.is_some()) {
        sink.error(
            &path,
            "records whose width a field gives take no count from the request (not expressible yet)",
        );
        return None;
    }
    if f.repeat.as_ref().is_some_and(|r| r.count != "end") {
        sink.error(
            &path,
            "a record whose width a field gives runs to the `end` of the frame (count: end); counted records of it are not expressible yet",
        );
        return None;
    }
    match earlier.iter().position(|e| e.name == by) {
        Some(i)
            if plain_unsigned(&earlier[i])
                && earlier[i].equals.is_none()
                && earlier[i].follows.is_none()
                && earlier[i].constant.is_none() =>
        {
            Some(i)
        }
        Some(_) => {
            sink.error(
                &path,
                format!("`{by}` is not an unsigned number field the sender sets"),
            );
            None
        }
        None => {
            sink.error(
                &path,
                format!("refers to `{by}`, which is not an earlier field of this message"),
            );
            None
        }
    }
}

/// `ceil(name × multiply / divide)`, each factor 1..=65535 (default 1).
fn relation(
    name: &str,
    multiply: Option<i64>,
    divide: Option<i64>,
    path: &str,
    sink: &mut Sink,
) -> Relation {
    let (mul, div) = (multiply.unwrap_or(1), divide.unwrap_or(1));
    if !(1..=0xFFFF).contains(&mul) || !(1..=0xFFFF).contains(&div) {
        sink.error(
            path,
            format!("multiply {mul} and divide {div} must be 1..=65535"),
        );
    }
    Relation {
        field: name.to_owned(),
        multiply: mul.clamp(1, 0xFFFF) as u64,
        divide: div.clamp(1, 0xFFFF) as u64,
    }
}

/// Resolves a field's `repeat`: its count against the earlier fields, its bounds.
fn repeat(
    r: &model::Repeat,
    f: &model::Field,
    p: &str,
    earlier: &[Field],
    sink: &mut Sink,
) -> Option<Repeat> {
    let of = r.of.unwrap_or(model::CountOf::Elements);
    // A fixed count reaches here only on records ([`fixed_list`] checked it and took every
    // other list of a fixed count): exactly that many.
    let fixed = r
        .count
        .parse::<i64>()
        .ok()
        .filter(|n| (1..=MAX_PACKED).contains(n));
    let Some(max) = r.max.or(fixed) else {
        sink.error(
            p,
            "missing field `max` (the most elements a frame may carry; only a fixed count, `count: 4`, needs none)",
        );
        return None;
    };
    if !(1..=0xFFFF).contains(&max) {
        sink.error(
            join(p, "max"),
            format!("a repeat's maximum is 1..=65535 elements, not {max}"),
        );
        return None;
    }
    let min = r.min.or(fixed).unwrap_or(0);
    if !(0..=max).contains(&min) {
        sink.error(
            join(p, "min"),
            format!("a repeat's minimum {min} is outside 0..={max}"),
        );
        return None;
    }
    let count = if let Some(t) = r.until {
        let refused = if !r.count.is_empty() {
            Some((
                "count",
                "`until` and `count` are two ways to end a list: give one",
            ))
        } else if r.of.is_some() {
            Some((
                "of",
                "`of` says what a count field counts; text up to a terminator has none",
            ))
        } else if r.request.is_some() {
            Some((
                "request",
                "text up to a terminator takes no count from the request (its terminator ends it)",
            ))
        } else if f.ty != model::FieldType::Ascii {
            Some((
                "until",
                "a terminator ends text (type: ascii); a list of numbers is counted by a field or runs to the `end`",
            ))
        } else {
            None
        };
        if let Some((k, why)) = refused {
            sink.error(join(p, k), why);
            return None;
        }
        match u8::try_from(t) {
            Ok(t) => Count::Until(t),
            Err(_) => {
                sink.error(
                    join(p, "until"),
                    format!("a terminator is one byte, 0x00..=0xFF, not {t}"),
                );
                return None;
            }
        }
    } else if r.count.is_empty() {
        sink.error(
            p,
            "a repeat needs `count` (an earlier field, `end`, or a number of elements) or, for text, `until` (its terminator byte)",
        );
        return None;
    } else if r.count == "end" {
        if r.of.is_some() {
            sink.error(
                join(p, "of"),
                "`of` says what a count field counts; `end` has none",
            );
        }
        Count::ToEnd
    } else if let Some(n) = fixed {
        Count::Fixed(n as usize)
    } else {
        match earlier.iter().position(|e| e.name == r.count) {
            Some(i) if plain_unsigned(&earlier[i]) => match of {
                model::CountOf::Elements => Count::Elements(i),
                model::CountOf::Bytes => Count::Bytes(i),
            },
            Some(_) => {
                sink.error(
                    join(p, "count"),
                    format!("`{}` is not an unsigned number field", r.count),
                );
                return None;
            }
            None => {
                sink.error(
                    join(p, "count"),
                    format!(
                        "refers to `{}`, which is not an earlier field of this message (or `end`)",
                        r.count
                    ),
                );
                return None;
            }
        }
    };
    if f.ty == model::FieldType::Bit && matches!(count, Count::Elements(_)) {
        sink.error(
            join(p, "of"),
            "bits pack eight to a byte: count them in `bytes` (or to the `end`)",
        );
    }
    let request = r.request.as_ref().map(|rel| {
        relation(
            &rel.field,
            rel.multiply,
            rel.divide,
            &join(p, "request"),
            sink,
        )
    });
    Some(Repeat {
        count,
        min: min as usize,
        max: max as usize,
        request,
    })
}

/// A range of an integer field as integers (up to `i64::MAX`; a `u64` field's may go higher,
/// see [`wide_field`]).
fn int_range(r: model::FieldRange, p: &str, sink: &mut Sink) -> Option<model::Range> {
    let mut ok = true;
    let mut end = |k: &str, b: model::Bound| match b {
        model::Bound::Int(v) => v,
        model::Bound::Uint(v) => {
            sink.error(join(p, k), format!("{k} {v} does not fit the field's type"));
            ok = false;
            0
        }
        model::Bound::Float(v) => {
            sink.error(
                join(p, k),
                format!("{k} {v} is not an integer: a range is raw wire integers (decimals only for f32 and f64)"),
            );
            ok = false;
            0
        }
    };
    let r = model::Range {
        min: end("min", r.min),
        max: end("max", r.max),
    };
    ok.then_some(r)
}

/// Refuses each of `keys` (in this order) that the field sets, at its path, worded by `why`;
/// whether it refused any.
fn refuse_keys(
    f: &model::Field,
    p: &str,
    keys: &[&str],
    why: impl Fn(&str) -> String,
    sink: &mut Sink,
) -> bool {
    let mut any = false;
    for &k in keys {
        if f.sets(k) {
            any = true;
            sink.error(join(p, k), why(k));
        }
    }
    any
}

/// A BCD field (`encoding: bcd`): an unsigned number of 1 to 4 bytes with a `unit` and a
/// `range` within what its digits hold (that range when none is given); nothing else yet.
fn bcd_field(f: &model::Field, p: &str, mut out: Field, refs: &Refs, sink: &mut Sink) -> Field {
    use model::FieldType as T;
    if !matches!(f.ty, T::U8 | T::U16 | T::U24 | T::U32) {
        sink.error(
            join(p, "encoding"),
            "`encoding: bcd` is for unsigned fields of 1 to 4 bytes (u8 u16 u24 u32)",
        );
        return out;
    }
    refuse_keys(
        f,
        p,
        &[
            "value", "enum", "flags", "equals", "special", "bits", "repeat", "follows",
        ],
        |k| format!("`{k}` cannot be combined with `encoding: bcd` (not expressible yet)"),
        sink,
    );
    let most = 10i64.pow(2 * out.width as u32) - 1;
    match &f.unit {
        Some(u) => match refs.units.get(u) {
            Some(i) => out.unit = Some(i),
            None => sink.error(
                join(p, "unit"),
                format!("refers to unit `{u}`, which is not defined in `units`"),
            ),
        },
        None => sink.error(p, "a BCD field needs a `unit`"),
    }
    let Some(r) = f.range else {
        out.range = Some((0, most));
        return out;
    };
    let rp = join(p, "range");
    let mut ok = true;
    let mut end = |k: &str, b: model::Bound| -> i64 {
        match b {
            model::Bound::Int(v) if (0..=most).contains(&v) => v,
            _ => {
                let shown = match b {
                    model::Bound::Int(v) => v.to_string(),
                    model::Bound::Uint(v) => v.to_string(),
                    model::Bound::Float(v) => v.to_string(),
                };
                sink.error(
                    join(&rp, k),
                    format!(
                        "{k} {shown} does not fit the field: its {} BCD digits hold 0..={most}",
                        2 * out.width
                    ),
                );
                ok = false;
                0
            }
        }
    };
    let (min, max) = (end("min", r.min), end("max", r.max));
    if ok && min > max {
        sink.error(&rp, format!("range is empty: min {min} > max {max}"));
    } else if ok {
        out.range = Some((min, max));
    }
    out
}

/// A list of a fixed number of elements (`repeat: {count: 4}`): `f` without its `repeat`
/// (checked here), validated by [`field`] as one element, and the count, which
/// [`fixed_elements`] then makes packed elements of whole bytes of. Any other field as it is,
/// and no count. Elements are numbers of every width (signed, 24- and 64-bit, floats in their
/// word order), enum and unit typed; records, text and bits of a fixed count are refused at
/// the field's type.
fn fixed_list(f: &model::Field, p: &str, sink: &mut Sink) -> (model::Field, Option<usize>) {
    use model::FieldType as T;
    let Some(r) = &f.repeat else {
        return (f.clone(), None);
    };
    let Ok(n) = r.count.parse::<i64>() else {
        return (f.clone(), None);
    };
    let rp = join(p, "repeat");
    let mut out = f.clone();
    out.repeat = None;
    let refused = if !(1..=MAX_PACKED).contains(&n) {
        Some((
            "count",
            format!("a fixed count is 1..={MAX_PACKED} elements, not {n}"),
        ))
    } else if r.until.is_some() {
        Some((
            "until",
            "`until` and `count` are two ways to end a list: give one".to_owned(),
        ))
    } else if r.of.is_some() {
        Some((
            "of",
            "`of` says what a count field counts; a fixed count is of elements".to_owned(),
        ))
    } else if r.request.is_some() {
        Some((
            "request",
            "a fixed count takes nothing from the request".to_owned(),
        ))
    } else if let Some((k, v)) = [("min", r.min), ("max", r.max)]
        .into_iter()
        .find_map(|(k, v)| v.filter(|v| *v != n).map(|v| (k, v)))
    {
        Some((
            k,
            format!("a list of a fixed count of {n} holds {n} elements; `{k}: {v}` says otherwise (leave it out)"),
        ))
    } else if f.packed.is_some() {
        Some((
            "count",
            "`packed` gives its own count: leave out `repeat`".to_owned(),
        ))
    } else {
        None
    };
    if let Some((k, why)) = refused {
        sink.error(join(&rp, k), why);
        if f.ty == T::Record {
            // Checked on as one record, lest the rules of its repeat speak twice.
            out.repeat = Some(model::Repeat {
                count: "1".to_owned(),
                until: None,
                of: None,
                min: None,
                max: None,
                request: None,
            });
        }
        return (out, None);
    }
    // Records of a fixed count keep their repeat: the repeat machinery with a count no field
    // gives ([`Count::Fixed`], resolved by [`repeat`]).
    if f.ty == T::Record {
        return (f.clone(), None);
    }
    if matches!(f.ty, T::Ascii | T::Bit) {
        sink.error(
            join(p, "type"),
            format!(
                "a list of a fixed count (`count: {n}`) holds numbers (integers of 1 to 8 bytes, floats), each maybe of an enum or a unit, or records; {} elements are not expressible yet (a list counted by a field or to the `end` takes them)",
                format!("{:?}", f.ty).to_lowercase()
            ),
        );
        // Checked no further: a byte in its place, lest its type's own rules speak too.
        out.ty = T::U8;
        out.fields.clear();
        out.length = None;
        return (out, None);
    }
    refuse_keys(
        f,
        p,
        &[
            "value", "equals", "bits", "special", "follows", "encoding", "present",
        ],
        |k| format!("`{k}` cannot be combined with a list of a fixed count (not expressible yet)"),
        sink,
    );
    // Checked as one element without them (each refused once, above).
    out.value = None;
    out.equals = None;
    out.bits.clear();
    out.special.clear();
    out.follows = None;
    out.encoding = None;
    out.present = None;
    (out, Some(n as usize))
}

/// A list of `count` elements of `f`'s type (`repeat: {count}`, [`fixed_list`]), `f` validated
/// as one element: packed elements of whole bytes, each in the protocol's byte order (and the
/// field's word order).
fn fixed_elements(f: &mut Field, count: usize) {
    f.packed = Some(Packed {
        count,
        bits: 8 * f.width as u32,
        lsb_first: f.byte_order == ByteOrder::Little,
        elem_width: f.width,
    });
    f.width *= count;
}

/// Packed elements (`packed: {count, bits, bit_order}`): `count` unsigned elements of the
/// field's type (u8, u16, u32), each `bits` wide (2 up to the type's width), packed into one
/// bit stream of `ceil(count × bits / 8)` bytes; a `unit` and a `range` (within `bits`) apply to
/// every element. Nothing else combines with it yet.
fn packed_field(
    f: &model::Field,
    pk: &model::Packed,
    p: &str,
    mut out: Field,
    refs: &Refs,
    sink: &mut Sink,
) -> Field {
    use model::FieldType as T;
    let pp = join(p, "packed");
    let elem_width = match f.ty {
        T::U8 => 1,
        T::U16 => 2,
        T::U32 => 4,
        _ => {
            sink.error(
                join(p, "type"),
                "packed elements are unsigned integers: u8, u16 or u32 (the element type holds one element)",
            );
            return out;
        }
    };
    refuse_keys(
        f,
        p,
        &[
            "repeat",
            "value",
            "enum",
            "flags",
            "equals",
            "bits",
            "special",
            "follows",
            "word_order",
            "encoding",
        ],
        |k| format!("`{k}` cannot be combined with `packed`"),
        sink,
    );
    let type_bits = 8 * elem_width as i64;
    // Its bytes as written, even where a rule below refuses it: the errors about the payload's
    // size then follow from what the spec says, not from a placeholder.
    if (1..=MAX_PACKED).contains(&pk.count) && (1..=64).contains(&pk.bits) {
        out.width = ((pk.count * pk.bits) as usize).div_ceil(8);
    }
    if !(2..=type_bits).contains(&pk.bits) {
        sink.error(
            join(&pp, "bits"),
            format!(
                "a packed {} element is 2..={type_bits} bits wide, not {} (1-bit elements are `type: bit` with a `repeat`)",
                match elem_width {
                    1 => "u8",
                    2 => "u16",
                    _ => "u32",
                },
                pk.bits
            ),
        );
        return out;
    }
    if !(1..=MAX_PACKED).contains(&pk.count) {
        sink.error(
            join(&pp, "count"),
            format!("packed elements number 1..={MAX_PACKED}, not {}", pk.count),
        );
        return out;
    }
    let packed = Packed {
        count: pk.count as usize,
        bits: pk.bits as u32,
        lsb_first: pk.bit_order == model::BitOrder::LsbFirst,
        elem_width,
    };
    out.width = packed.bytes();
    out.packed = Some(packed);
    match &f.unit {
        Some(u) => match refs.units.get(u) {
            Some(i) => out.unit = Some(i),
            None => sink.error(
                join(p, "unit"),
                format!("refers to unit `{u}`, which is not defined in `units`"),
            ),
        },
        None => sink.error(join(p, "unit"), "packed elements need a `unit`"),
    }
    out.range = f
        .range
        .and_then(|r| int_range(r, &join(p, "range"), sink))
        .and_then(|r| range(r, pk.bits as u32, false, &join(p, "range"), sink));
    out
}

/// A 64-bit integer or float field: a plain number, with a `unit` whose scale is 1 and offset
/// 0 (the raw value is the physical one), a `range` and a `word_order`, maybe repeated (a list
/// counted by a field, in bytes or to the `end`, each element as such a field); nothing else yet.
fn wide_field(
    f: &model::Field,
    p: &str,
    mut out: Field,
    earlier: &[Field],
    refs: &Refs,
    sink: &mut Sink,
) -> Field {
    use model::FieldType as T;
    let what = match f.ty {
        T::F32 | T::F64 => "a float",
        _ => "a 64-bit integer",
    };
    refuse_keys(
        f,
        p,
        &[
            "value", "enum", "flags", "equals", "special", "bits", "follows",
        ],
        |k| format!("`{k}` cannot be combined with {what} field (not expressible yet)"),
        sink,
    );
    if let Some(r) = &f.repeat {
        out.repeat = repeat(r, f, &join(p, "repeat"), earlier, sink);
    }
    match &f.unit {
        Some(u) => match refs.units.get(u) {
            Some(i) => {
                let unit = &refs.unit_defs[i];
                if unit.scale != Rational::int(1) || unit.offset != Rational::ZERO {
                    sink.error(
                        join(p, "unit"),
                        format!(
                            "unit `{u}` has scale {} and offset {}: {what} field takes a unit of scale 1 and offset 0 (its value as it travels is the physical value)",
                            unit.scale, unit.offset
                        ),
                    );
                }
                out.unit = Some(i);
            }
            None => sink.error(
                join(p, "unit"),
                format!("refers to unit `{u}`, which is not defined in `units`"),
            ),
        },
        None => sink.error(p, format!("{what} field needs a `unit`")),
    }
    let Some(r) = f.range else {
        return out;
    };
    let rp = join(p, "range");
    let kind = out.num_kind();
    let mut ok = true;
    let mut end = |k: &str, b: model::Bound| -> i64 {
        let raw = match (f.ty, b) {
            (T::I64, model::Bound::Int(v)) => Some(v),
            (T::U64, model::Bound::Int(v)) if v >= 0 => Some(v),
            (T::U64, model::Bound::Uint(v)) => Some(v as i64),
            (T::F32, model::Bound::Int(v)) => Some(i64::from((v as f32).to_bits())),
            (T::F32, model::Bound::Uint(v)) => Some(i64::from((v as f32).to_bits())),
            (T::F32, model::Bound::Float(v)) if v.is_finite() => {
                Some(i64::from((v as f32).to_bits()))
                    .filter(|r| kind.float(*r).is_some_and(f64::is_finite))
            }
            (T::F64, model::Bound::Int(v)) => Some((v as f64).to_bits() as i64),
            (T::F64, model::Bound::Uint(v)) => Some((v as f64).to_bits() as i64),
            (T::F64, model::Bound::Float(v)) if v.is_finite() => Some(v.to_bits() as i64),
            _ => None,
        };
        raw.unwrap_or_else(|| {
            let shown = match b {
                model::Bound::Int(v) => v.to_string(),
                model::Bound::Uint(v) => v.to_string(),
                model::Bound::Float(v) => v.to_string(),
            };
            let why = if out.is_float() {
                "a float's range is finite numbers of its type"
            } else {
                "a 64-bit integer's range is integers of its type"
            };
            sink.error(
                join(&rp, k),
                format!("{k} {shown} does not fit the field: {why}"),
            );
            ok = false;
            0
        })
    };
    let (min, max) = (end("min", r.min), end("max", r.max));
    if !ok {
        return out;
    }
    if !kind.within(min, min, max) {
        sink.error(
            &rp,
            format!(
                "range is empty: min {} > max {}",
                kind.text(min),
                kind.text(max)
            ),
        );
        return out;
    }
    out.range = Some((min, max));
    out
}

fn range(r: model::Range, bits: u32, signed: bool, p: &str, sink: &mut Sink) -> Option<(i64, i64)> {
    let (lo, hi) = raw_limits(bits, signed);
    let mut ok = true;
    for (k, v) in [("min", r.min), ("max", r.max)] {
        if v < lo || v > hi {
            sink.error(
                join(p, k),
                format!(
                    "{k} {v} does not fit in a {}{bits}-bit field ({lo}..={hi})",
                    if signed { "signed " } else { "" }
                ),
            );
            ok = false;
        }
    }
    if r.min > r.max {
        sink.error(p, format!("range is empty: min {} > max {}", r.min, r.max));
        ok = false;
    }
    ok.then_some((r.min, r.max))
}

fn bit_fields(
    bits: &[model::BitField],
    total: u32,
    p: &str,
    refs: &Refs,
    sink: &mut Sink,
) -> Vec<BitField> {
    let mut covered = 0u64;
    let mut out = Vec::new();
    for b in bits {
        let bp = join(&join(p, "bits"), &b.name);
        check_ident(&b.name, &bp, "field", sink);
        if b.lsb < 0 || b.msb < b.lsb || b.msb >= i64::from(total) {
            sink.error(&bp, format!("bits {}..{} are not a range inside a {total}-bit field (msb >= lsb, msb < {total})", b.msb, b.lsb));
            continue;
        }
        let (msb, lsb) = (b.msb as u8, b.lsb as u8);
        let w = u32::from(msb - lsb + 1);
        let mask = (if w >= 64 { u64::MAX } else { (1u64 << w) - 1 }) << lsb;
        if covered & mask != 0 {
            sink.error(&bp, format!("bits {msb}..{lsb} overlap another sub-field"));
        }
        covered |= mask;
        let mut bf = BitField {
            name: b.name.clone(),
            doc: text(&b.doc),
            msb,
            lsb,
            signed: b.signed,
            unit: None,
            range: None,
            constant: None,
        };
        if let Some(v) = b.value {
            if b.unit.is_some() || b.range.is_some() || b.signed {
                sink.error(
                    &bp,
                    "a constant sub-field takes no unit, range or signedness",
                );
            }
            if fits_unsigned(v, w) {
                bf.constant = Some(v as u64);
            } else {
                sink.error(
                    join(&bp, "value"),
                    format!("constant {v} does not fit in {w} bits"),
                );
            }
        } else {
            match &b.unit {
                Some(u) => match refs.units.get(u) {
                    Some(i) => bf.unit = Some(i),
                    None => sink.error(
                        join(&bp, "unit"),
                        format!("refers to unit `{u}`, which is not defined in `units`"),
                    ),
                },
                None => sink.error(&bp, "a sub-field needs a `unit` (or a constant `value`)"),
            }
            bf.range = b
                .range
                .and_then(|r| range(r, w, b.signed, &join(&bp, "range"), sink));
        }
        out.push(bf);
    }
    let full = if total >= 64 {
        u64::MAX
    } else {
        (1u64 << total) - 1
    };
    if covered != full && !out.is_empty() {
        let missing: Vec<String> = (0..total)
            .rev()
            .filter(|i| covered & (1 << i) == 0)
            .map(|i| i.to_string())
            .collect();
        sink.error(
            join(p, "bits"),
            format!(
                "sub-fields must cover all {total} bits; bits {} are not covered",
                missing.join(", ")
            ),
        );
    }
    out
}

/// The fixed bits of a frame from its code on (the code, then the payload without a repeated
/// field's elements): for each byte, a mask of the bits fixed by the code, a constant field or a
/// constant sub-field, and their values. A code-less message's template starts where a coded
/// one's code does, so templates of one direction line up byte for byte.
fn template(m: &Message) -> Vec<(u8, u8)> {
    // Fields after a list sit where its elements end: the template stops at the first list.
    let fixed = m.repeat().map_or(m.payload_len, |(f, _)| f.offset);
    let mut t = vec![(0u8, 0u8); m.code.len() + fixed];
    for (slot, b) in t.iter_mut().zip(&m.code) {
        *slot = (0xFF, *b);
    }
    // Header fields sit outside the code and payload: their fixed bits are not in it.
    for f in m.fields.iter().filter(|f| !f.header) {
        if f.repeat.is_some() {
            break;
        }
        if f.width == 0 || f.width > 8 {
            continue;
        }
        let ones = |bits: u32| {
            if bits >= 64 {
                u64::MAX
            } else {
                (1u64 << bits) - 1
            }
        };
        let (mask, value) = match f.constant {
            Some(c) => (ones(8 * f.width as u32), c),
            None => f.bits.iter().filter_map(|b| Some((b, b.constant?))).fold(
                (0u64, 0u64),
                |(mask, value), (b, c)| {
                    let m = ones(u32::from(b.width()))
                        .checked_shl(u32::from(b.lsb))
                        .unwrap_or(0);
                    (
                        mask | m,
                        value | (c.checked_shl(u32::from(b.lsb)).unwrap_or(0) & m),
                    )
                },
            ),
        };
        if mask == 0 {
            continue;
        }
        let (mut mb, mut vb) = ([0u8; 8], [0u8; 8]);
        interp::write_uint(mask, &mut mb[..f.width], f.byte_order);
        interp::write_uint(value & mask, &mut vb[..f.width], f.byte_order);
        let at = m.code.len() + f.offset;
        for (k, slot) in t.iter_mut().skip(at).take(f.width).enumerate() {
            *slot = (mb[k], vb[k]);
        }
    }
    t
}

/// Whether some frame fits both templates: no bit both fix differs.
fn compatible(a: &[(u8, u8)], b: &[(u8, u8)]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(&(ma, va), &(mb, vb))| (va ^ vb) & ma & mb == 0)
}

/// Whether some frame fits both templates where they overlap (a variable message's template is
/// followed by its repeated elements, which fit anything).
fn compatible_prefix(a: &[(u8, u8)], b: &[(u8, u8)]) -> bool {
    a.iter()
        .zip(b)
        .all(|(&(ma, va), &(mb, vb))| (va ^ vb) & ma & mb == 0)
}

/// The shortest and longest frame of a message.
fn len_range(m: &Message) -> (usize, usize) {
    (m.min_len(), m.max_len)
}

/// Clash errors reported for one list at most; past this the spec is hostile or generated
/// wrong, and listing every pair of thousands of messages would take quadratic time and memory.
pub const MAX_CLASH_ERRORS: usize = 1000;

/// Two messages of one direction clash when a frame of the same length fits both templates
/// (code-less messages included: their template lines up with a coded one's code and payload),
/// unless both are `needs_request`; a code that is a proper prefix of another is an error of
/// its own.
///
/// Close to linear: only messages of one template length are compared, identical templates are
/// grouped (every pair within a group clashes), and distinct templates are split by a byte every
/// one of them fixes ([`compatible_templates`]); prefixes are looked up in a map of codes.
///
/// A message with a repeated field (variable length) is compared with every message whose frame
/// lengths overlap its own (`len_range`) and that has its code or none, over the bytes both
/// templates cover: its elements may hold anything. That is quadratic only in code-less
/// variable messages, of which a real spec has one or two.
fn check_overlaps(msgs: &[Message], list: &str, sink: &mut Sink) {
    use std::collections::HashMap;
    let templates: Vec<Vec<(u8, u8)>> = msgs.iter().map(template).collect();

    // Identical templates, by template length (first appearance order, for determinism).
    let mut class_of: HashMap<&[(u8, u8)], usize> = HashMap::new();
    let mut classes: Vec<Vec<usize>> = Vec::new();
    for (i, t) in templates.iter().enumerate() {
        if msgs[i].is_variable() {
            continue;
        }
        let c = *class_of.entry(t.as_slice()).or_insert_with(|| {
            classes.push(Vec::new());
            classes.len() - 1
        });
        classes[c].push(i);
    }
    let mut by_len: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (c, members) in classes.iter().enumerate() {
        by_len
            .entry(templates[members[0]].len())
            .or_default()
            .push(c);
    }
    let rep = |c: usize| templates[classes[c][0]].as_slice();
    let mut class_pairs: Vec<(usize, usize)> = (0..classes.len()).map(|c| (c, c)).collect();
    for group in by_len.into_values() {
        compatible_templates(&rep, group, &mut class_pairs);
    }

    // The message pairs that clash, and `needs_request` messages another of their code fits.
    let mut clashes: Vec<(usize, usize)> = Vec::new();
    let mut capped = false;
    let mut shared = vec![false; msgs.len()];
    let prefix = |a: &Message, b: &Message| {
        let (short, long) = if a.code.len() <= b.code.len() {
            (a, b)
        } else {
            (b, a)
        };
        !short.code.is_empty()
            && short.code.len() < long.code.len()
            && long.code.starts_with(&short.code)
    };
    // Looks at one pair of messages that a frame of one length may fit both of; false once
    // capped.
    let mut consider = |i: usize, j: usize| {
        let (a, b) = (&msgs[i], &msgs[j]);
        if a.code == b.code {
            shared[i] = true;
            shared[j] = true;
        }
        if (a.needs_request && b.needs_request) || prefix(a, b) {
            return true;
        }
        if clashes.len() == MAX_CLASH_ERRORS {
            capped = true;
            return false;
        }
        clashes.push((i.min(j), i.max(j)));
        true
    };
    'pairs: for (ca, cb) in class_pairs {
        for (x, &i) in classes[ca].iter().enumerate() {
            let from = if ca == cb { x + 1 } else { 0 };
            for &j in &classes[cb][from..] {
                if !consider(i, j) {
                    break 'pairs;
                }
            }
        }
    }
    // Variable messages, against those of their code and the code-less.
    let mut coded: HashMap<&[u8], Vec<usize>> = HashMap::new();
    let mut codeless: Vec<usize> = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        if m.code.is_empty() {
            codeless.push(i);
        } else {
            coded.entry(m.code.as_slice()).or_default().push(i);
        }
    }
    'variable: for (j, v) in msgs.iter().enumerate().filter(|(_, m)| m.is_variable()) {
        let (lo, hi) = len_range(v);
        let others: &[usize] = if v.code.is_empty() {
            &[]
        } else {
            coded.get(v.code.as_slice()).map_or(&[][..], Vec::as_slice)
        };
        let all: Vec<usize>;
        let candidates: Box<dyn Iterator<Item = usize> + '_> = if v.code.is_empty() {
            all = (0..msgs.len()).collect();
            Box::new(all.iter().copied())
        } else {
            Box::new(others.iter().chain(&codeless).copied())
        };
        for i in candidates {
            let o = &msgs[i];
            // Each pair once: a variable pair from its later message.
            if i == j || (o.is_variable() && i > j) {
                continue;
            }
            let (olo, ohi) = len_range(o);
            if olo > hi || lo > ohi || !compatible_prefix(&templates[i], &templates[j]) {
                continue;
            }
            if !consider(i, j) {
                break 'variable;
            }
        }
    }
    // Proper prefixes of every code, looked up among the codes.
    let mut by_code: HashMap<&[u8], Vec<usize>> = HashMap::new();
    for (i, m) in msgs.iter().enumerate() {
        if !m.code.is_empty() {
            by_code.entry(m.code.as_slice()).or_default().push(i);
        }
    }
    let mut prefixes: Vec<(usize, usize)> = Vec::new();
    'prefix: for (j, m) in msgs.iter().enumerate() {
        for k in 1..m.code.len() {
            for &i in by_code.get(&m.code[..k]).map_or(&[][..], Vec::as_slice) {
                if prefixes.len() == MAX_CLASH_ERRORS {
                    capped = true;
                    break 'prefix;
                }
                prefixes.push((i.min(j), i.max(j)));
            }
        }
    }

    // Reported in the order of the pairs, as comparing every pair in order would.
    let mut pairs: Vec<(usize, usize, bool)> = clashes
        .into_iter()
        .map(|(i, j)| (i, j, false))
        .chain(prefixes.into_iter().map(|(i, j)| (i, j, true)))
        .collect();
    pairs.sort_unstable();
    for (i, j, is_prefix) in pairs {
        let (a, b) = (&msgs[i], &msgs[j]);
        let path = join(list, &b.name);
        if is_prefix {
            let (short, long) = if a.code.len() <= b.code.len() {
                (a, b)
            } else {
                (b, a)
            };
            sink.error(
                path,
                format!(
                    "code {} of `{}` is a prefix of code {} of `{}`: a receiver could not tell where the code ends",
                    short.code_hex(), short.name, long.code_hex(), long.name
                ),
            );
            continue;
        }
        let how = if a.code == b.code {
            "duplicate code"
        } else {
            "overlapping codes"
        };
        // A code-less message fits every code: say so, not `0x`.
        let code = |m: &Message| {
            if m.code.is_empty() {
                "no code".to_owned()
            } else {
                m.code_hex()
            }
        };
        sink.error(
            path,
            format!(
                "{how}: `{}` ({}) and `{}` ({}) have the same length and no constant field tells them apart{}",
                a.name,
                code(a),
                b.name,
                code(b),
                if list == "responses" { " (if only the request can tell them apart, mark both `needs_request: true`)" } else { "" }
            ),
        );
    }
    if capped {
        sink.error(
            list,
            format!(
                "more than {MAX_CLASH_ERRORS} pairs of messages clash; the rest are not listed"
            ),
        );
    }
    // Once capped, not every pair was looked at: a lone `needs_request` may have a partner.
    for (i, m) in msgs.iter().enumerate() {
        if m.needs_request && !shared[i] && !capped {
            sink.error(
                join(list, &m.name),
                "`needs_request` is set, but no other response shares its code and length",
            );
        }
    }
}

/// Adds to `out` every pair `(a, b)`, `a < b`, of the distinct templates `group` (all of one
/// length, each named by `rep`) that some frame fits. A byte that most of them fix fully (with
/// at least two values) splits them: those fixing it are compared only with those fixing the
/// same value, and the others with all. What no byte splits is compared pair by pair.
fn compatible_templates<'t>(
    rep: &impl Fn(usize) -> &'t [(u8, u8)],
    group: Vec<usize>,
    out: &mut Vec<(usize, usize)>,
) {
    let pairwise = |group: &[usize], out: &mut Vec<(usize, usize)>| {
        for (x, &a) in group.iter().enumerate() {
            for &b in &group[x + 1..] {
                if compatible(rep(a), rep(b)) {
                    out.push((a.min(b), a.max(b)));
                }
            }
        }
    };
    if group.len() < 8 {
        pairwise(&group, out);
        return;
    }
    let len = rep(group[0]).len();
    // The byte fixed in the most templates, among those fixed to at least two values.
    let mut best: Option<(usize, usize)> = None;
    for p in 0..len {
        let mut fixed = 0;
        let mut first: Option<u8> = None;
        let mut two = false;
        for &c in &group {
            let (m, v) = rep(c)[p];
            if m == 0xFF {
                fixed += 1;
                match first {
                    None => first = Some(v),
                    Some(f) => two |= f != v,
                }
            }
        }
        if two && best.map_or(true, |(_, n)| fixed > n) {
            best = Some((p, fixed));
        }
    }
    let Some((p, _)) = best else {
        pairwise(&group, out);
        return;
    };
    let (fixed, wild): (Vec<usize>, Vec<usize>) = group.iter().partition(|&&c| rep(c)[p].0 == 0xFF);
    for (x, &w) in wild.iter().enumerate() {
        for &c in wild[x + 1..].iter().chain(&fixed) {
            if compatible(rep(w), rep(c)) {
                out.push((w.min(c), w.max(c)));
            }
        }
    }
    let mut buckets: BTreeMap<u8, Vec<usize>> = BTreeMap::new();
    for c in fixed {
        buckets.entry(rep(c)[p].1).or_default().push(c);
    }
    for bucket in buckets.into_values() {
        compatible_templates(rep, bucket, out);
    }
}

fn stated(v: &model::OpenValue) -> Result<StatedValue, String> {
    use model::OpenValue as V;
    match v {
        V::Number(t) => Ok(match Rational::parse(t) {
            // A negative zero keeps its sign for a float field.
            Ok(n) if n == Rational::ZERO && t.trim_start().starts_with('-') => StatedValue::Exact {
                text: t.clone(),
                why: String::new(),
            },
            Ok(n) => StatedValue::Number(n),
            Err(why) => StatedValue::Exact {
                text: t.clone(),
                why,
            },
        }),
        V::String(s) => Ok(StatedValue::Name(s.clone())),
        V::List(items) if items.iter().any(|i| matches!(i, V::Map(_))) => items
            .iter()
            .map(|i| match i {
                V::Map(m) => {
                    m.0.iter()
                        .map(|(k, v)| {
                            let k = k
                                .as_str()
                                .ok_or_else(|| "a record's keys are its field names".to_owned())?;
                            Ok((k.to_owned(), stated(v)?))
                        })
                        .collect::<Result<Vec<_>, String>>()
                }
                _ => Err("a list of records holds something else".to_owned()),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(StatedValue::Records),
        V::List(items) if items.iter().any(|i| matches!(i, V::Number(_))) => items
            .iter()
            .map(|i| match i {
                V::Number(t) => Rational::parse(t),
                _ => Err("a list of numbers holds something else".to_owned()),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(StatedValue::Numbers),
        V::List(items) => items
            .iter()
            .map(|i| {
                i.as_str()
                    .map(str::to_owned)
                    .ok_or_else(|| "a list of flag names holds something else".to_owned())
            })
            .collect::<Result<Vec<_>, _>>()
            .map(StatedValue::Names),
        other => Err(format!(
            "a stated value must be a number, a name, text or a list of flag names, found {}",
            other.kind()
        )),
    }
}

fn examples(spec: &model::Spec, p: &Protocol, sink: &mut Sink) -> Vec<Example> {
    use std::collections::HashMap;
    let mut out = Vec::new();
    if spec.examples.is_empty() {
        return out;
    }
    // Names looked up once, not once an example: a spec may have thousands of each.
    let mut messages: HashMap<&str, MessageRef> = HashMap::new();
    for direction in [Direction::Response, Direction::Request] {
        for (index, m) in p.messages(direction).iter().enumerate().rev() {
            messages.insert(&m.name, MessageRef { direction, index });
        }
    }
    let commands: HashMap<&str, usize> = (p.commands.iter().enumerate().rev())
        .map(|(i, c)| (c.name.as_str(), i))
        .collect();
    let errata: HashMap<&str, usize> = (p.errata.iter().enumerate().rev())
        .map(|(i, x)| (x.id.as_str(), i))
        .collect();
    // Each direction's lookup, for decoding a frame without being told what it is.
    let lookups = [
        interp::Lookup::new(p, Some(Direction::Request)),
        interp::Lookup::new(p, Some(Direction::Response)),
    ];
    for (i, e) in spec.examples.iter().enumerate() {
        let path = format!("examples[{i}]");
        let Some(&r) = messages.get(e.message.as_str()) else {
            sink.error(
                join(&path, "message"),
                format!("refers to message `{}`, which is not defined", e.message),
            );
            continue;
        };
        let m = p.message(r);
        let lookup = match r.direction {
            Direction::Request => &lookups[0],
            Direction::Response => &lookups[1],
        };
        let at = format!("§{} {}", e.section, m.name);
        let reply_to = match (&e.reply_to, r.direction) {
            (None, _) => {
                if m.needs_request {
                    sink.error(join(&path, "reply_to"), format!("{at}: `{}` can only be decoded with its request: say which with `reply_to`", m.name));
                }
                None
            }
            (Some(_), Direction::Request) => {
                sink.error(
                    join(&path, "reply_to"),
                    format!("{at}: only a response example answers a request"),
                );
                None
            }
            (Some(name), Direction::Response) => match commands.get(name.as_str()).copied() {
                Some(c) if p.commands[c].gets(r.index) => Some(c),
                Some(_) => {
                    sink.error(
                        join(&path, "reply_to"),
                        format!(
                            "{at}: command `{name}` does not list `{}` among its responses",
                            m.name
                        ),
                    );
                    None
                }
                None => {
                    sink.error(
                        join(&path, "reply_to"),
                        format!("{at}: refers to command `{name}`, which is not defined"),
                    );
                    None
                }
            },
        };
        if m.needs_request && reply_to.is_none() {
            // Already reported above; without its request the frame would only add "ambiguous".
            continue;
        }
        // The request's frame, where a reply's checksum takes in its bytes.
        let request = match (&e.request, reply_to) {
            (None, _) if m.over_request.is_some() => {
                sink.error(
                    join(&path, "request"),
                    format!("{at}: the checksum of `{}` takes in its request's bytes: give the request's frame with `request` (and the command with `reply_to`)", m.name),
                );
                continue;
            }
            (None, _) => None,
            (Some(_), None) => {
                sink.error(
                    join(&path, "request"),
                    format!("{at}: `request` is the frame of the request a reply example answers (`reply_to`)"),
                );
                continue;
            }
            (Some(text), Some(c)) => {
                let wire = match interp::parse_hex(text) {
                    Ok(w) => w,
                    Err(err) => {
                        sink.error(
                            join(&path, "request"),
                            format!("{at}: frame text `{text}`: {err}"),
                        );
                        continue;
                    }
                };
                match lookups[0].decode(p, None, &wire) {
                    Ok(f) if f.message.index == c => Some(wire),
                    Ok(f) => {
                        sink.error(
                            join(&path, "request"),
                            format!(
                                "{at}: the request decodes as `{}`, not `{}`",
                                p.message(f.message).name,
                                p.commands[c].name
                            ),
                        );
                        continue;
                    }
                    Err(err) => {
                        sink.error(
                            join(&path, "request"),
                            format!("{at}: the request does not decode: {err}"),
                        );
                        continue;
                    }
                }
            }
        };
        let covered = request.as_deref().and_then(|w| p.checksum_span(w));
        let erratum = match &e.erratum {
            None => None,
            Some(id) => {
                let found = errata.get(id.as_str()).copied();
                if found.is_none() {
                    sink.error(
                        join(&path, "erratum"),
                        format!(
                            "{at}: refers to erratum `{id}`, which is not recorded in `errata`"
                        ),
                    );
                }
                found
            }
        };
        let (source_key, source) = match (&e.printed, &e.derived) {
            (Some(t), None) => ("printed", t),
            (None, Some(t)) => ("derived", t),
            _ => {
                sink.error(&path, format!("{at}: give exactly one of `printed` (verbatim from the document) and `derived`"));
                continue;
            }
        };
        if e.corrected.is_some() && (e.printed.is_none() || e.erratum.is_none()) {
            sink.error(
                join(&path, "corrected"),
                format!("{at}: `corrected` belongs to a printed example with an `erratum`"),
            );
            continue;
        }
        let mut values = Vec::new();
        for (k, v) in &e.values {
            let Some(k) = k.as_str() else {
                sink.error(
                    join(&path, "values"),
                    format!("{at}: value keys are field names"),
                );
                continue;
            };
            if interp::leaf_field(m, k).is_none() {
                sink.error(
                    join(&join(&path, "values"), k),
                    format!(
                        "{at}: states a value for `{k}`, which `{}` does not have",
                        m.name
                    ),
                );
                continue;
            }
            match stated(v) {
                Ok(s) => values.push((k.to_owned(), s)),
                Err(msg) => sink.error(join(&join(&path, "values"), k), format!("{at}: {msg}")),
            }
        }
        // The printed frame must replay as it stands, or be excused by an erratum and corrected.
        let printed_check = frame_problems(
            p,
            lookup,
            r,
            (reply_to, covered),
            source,
            &values,
            e.erratum.is_some(),
        );
        let wire = match (printed_check, &e.corrected) {
            (Ok(wire), None) => wire,
            (Ok(_), Some(_)) => {
                sink.error(join(&path, "corrected"), format!("{at}: the printed frame replays as it stands; `corrected` is only for frames the document got wrong"));
                continue;
            }
            (Err(problem), None) => {
                let hint = if e.erratum.is_some() {
                    " (an erratum is cited: give the `corrected` frame)"
                } else {
                    ""
                };
                sink.error(join(&path, source_key), format!("{at}: {problem}{hint}"));
                continue;
            }
            (Err(_), Some(fixed)) if erratum.is_some() => {
                match frame_problems(p, lookup, r, (reply_to, covered), fixed, &values, true) {
                    Ok(wire) => wire,
                    Err(problem) => {
                        sink.error(join(&path, "corrected"), format!("{at}: {problem}"));
                        continue;
                    }
                }
            }
            (Err(_), Some(_)) => continue,
        };
        out.push(Example {
            section: e.section.clone(),
            message: r,
            reply_to,
            request,
            printed: e.printed.clone(),
            derived: e.derived.clone(),
            comment: e.comment.clone(),
            values,
            erratum,
            corrected: e.corrected.clone(),
            wire,
        });
    }
    out
}

/// Replays one example text as message `r`: length, start, code, checksum, constants, stated
/// values. Returns the wire bytes, or the first problem.
fn frame_problems(
    p: &Protocol,
    lookup: &interp::Lookup,
    r: MessageRef,
    (reply_to, covered): (Option<usize>, Option<&[u8]>),
    frame_text: &str,
    values: &[(String, StatedValue)],
    excused: bool,
) -> Result<Vec<u8>, String> {
    let m = p.message(r);
    let printed =
        interp::parse_hex(frame_text).map_err(|e| format!("frame text `{frame_text}`: {e}"))?;
    // Wake-up bytes before the frame (0 to the preamble's most): the frame follows them.
    let printed = p.framing.after_preamble(&printed);
    // An escaped frame is read unescaped, reordered, and escaped again.
    // By its direction's own escaped bytes (a response without start or end bytes is escaped
    // from its first byte to its last).
    let printed = crate::escape::unescape_bytes_of(&p.framing, m.direction, printed)
        .map_err(|e| format!("frame `{frame_text}`: {e}"))?;
    // Either form of a length field the start byte chooses, as the IR lays it out.
    let laid_out = crate::long::canonical(p, &printed)
        .map_err(|e| format!("frame `{frame_text}`: {e}"))?
        .frame;
    let len = p.frame_len(m);
    if m.is_variable() && (len..=m.max_len).contains(&laid_out.len()) {
        // Its repeated field's count is checked by decoding it.
    } else if laid_out.len() != len {
        return Err(format!(
            "frame `{frame_text}` has {} bytes, but a {} frame has {len} ({} overhead + {}-byte code + {} payload)",
            printed.len(),
            m.name,
            p.framing.overhead(m.direction),
            m.code.len(),
            m.payload_len
        ));
    }
    let wire = crate::escape::escape_bytes_of(
        &p.framing,
        m.direction,
        &interp::printed_to_wire(p, m, &printed),
    );
    let frame = interp::decode_as_reply(p, r, covered, &wire).map_err(|e| e.to_string())?;
    // The frame must also decode on its own, without being told what it is (as a sniffer would),
    // unless only its request can tell it apart.
    match lookup.decode_with(p, reply_to, covered, &wire) {
        Ok(f) if f.message == r => {}
        Ok(f) => {
            return Err(format!(
                "decodes as `{}`, not `{}`",
                p.message(f.message).name,
                m.name
            ))
        }
        Err(e) => return Err(format!("does not decode on its own: {e}")),
    }
    for (name, want) in values {
        let Some((field, bits)) = interp::leaf_field(m, name) else {
            return Err(format!(
                "states a value for `{name}`, which `{}` does not have",
                m.name
            ));
        };
        let Some(raw) = frame.get(name) else {
            return Err(format!("no value decoded for `{name}`"));
        };
        compare(p, field, bits, raw, want, excused).map_err(|e| format!("{name}: {e}"))?;
    }
    // The bytes an encoder sends: its preamble, then the frame.
    Ok(match &p.framing.preamble {
        Some(pre) => [vec![pre.byte; usize::from(pre.send)], wire].concat(),
        None => wire,
    })
}

fn compare(
    p: &Protocol,
    f: &Field,
    bits: Option<&BitField>,
    raw: &Raw,
    want: &StatedValue,
    excused: bool,
) -> Result<(), String> {
    let int = match raw {
        Raw::Text(t) => {
            let got = String::from_utf8_lossy(t);
            return match want {
                StatedValue::Name(s) if *s == got => Ok(()),
                StatedValue::Name(s) => Err(format!(
                    "the frame carries \"{got}\", the example states \"{s}\""
                )),
                _ => Err(format!(
                    "an ascii field; state it as text (the frame carries \"{got}\")"
                )),
            };
        }
        Raw::Int(i) if bits.is_none() && f.is_wide() => {
            // Read as the field's type: a decimal stated for a float is its nearest value (the
            // frame's bits must be exactly those), `inf`, `-inf`, `NaN` by name.
            let k = f.num_kind();
            let (stated, text) = match want {
                StatedValue::Number(n) => (k.parse(&n.to_string()), n.to_string()),
                StatedValue::Name(s) if f.is_float() => (k.parse(s), s.clone()),
                StatedValue::Exact { text, .. } => (k.parse(text), text.clone()),
                _ => {
                    return Err(format!(
                        "a number field; state a number (the frame carries {})",
                        k.text(*i)
                    ))
                }
            };
            return match stated {
                Some(w) if w == *i => Ok(()),
                Some(_) => Err(format!(
                    "the frame carries {}, the example states {text}",
                    k.text(*i)
                )),
                None => Err(format!("{text} is not a value of the field's type")),
            };
        }
        Raw::Int(i) => *i,
        Raw::Records(recs) => {
            let StatedValue::Records(want) = want else {
                return Err(
                    "a repeated record; state its records as a list of mappings of field names to values"
                        .to_owned(),
                );
            };
            if recs.len() != want.len() {
                return Err(format!(
                    "the frame carries {} records, the example states {}",
                    recs.len(),
                    want.len()
                ));
            }
            for (k, (rec, stated)) in recs.iter().zip(want).enumerate() {
                for (name, w) in stated {
                    let Some(j) = f.record.iter().position(|g| &g.name == name) else {
                        return Err(format!(
                            "record {k}: states `{name}`, which the record does not have"
                        ));
                    };
                    let (g, raw) = (&f.record[j], rec.get(j).copied().unwrap_or(0));
                    compare(p, g, None, &Raw::Int(raw), w, excused)
                        .map_err(|e| format!("record {k}: {name}: {e}"))?;
                }
            }
            return Ok(());
        }
        Raw::List(list) => {
            let StatedValue::Numbers(want) = want else {
                return Err("a repeated field; state its elements as a list of numbers".to_owned());
            };
            // Bits are decoded eight to a byte; the example may leave out the padding.
            let padded = f.ty == FieldType::Bit
                && list.len() >= want.len()
                && list.len() - want.len() < 8
                && list[want.len()..].iter().all(|&b| b == 0);
            if list.len() != want.len() && !padded {
                return Err(format!(
                    "the frame carries {} elements, the example states {}",
                    list.len(),
                    want.len()
                ));
            }
            for (k, (&raw, n)) in list.iter().zip(want).enumerate() {
                if f.is_wide() {
                    // 64-bit and float elements (a list of a fixed count): each read as its
                    // type, as a field of its own is.
                    let one = StatedValue::Number(*n);
                    compare(p, &f.element(), None, &Raw::Int(raw), &one, excused)
                        .map_err(|e| format!("element {k}: {e}"))?;
                    continue;
                }
                let got = match f.unit.map(|u| &p.units[u]) {
                    Some(u) => u.physical(raw),
                    None => Rational::int(i128::from(raw)),
                };
                if got != *n {
                    return Err(format!(
                        "element {k}: the frame carries {got} (raw {raw}), the example states {n}"
                    ));
                }
            }
            return Ok(());
        }
    };
    let (unit, range) = match bits {
        Some(b) => (b.unit, b.range),
        None => (f.unit, f.range),
    };
    // A special value (no sensor, defective) lies outside the range on purpose.
    let special = bits.is_none() && f.special.iter().any(|s| s.value == int);
    if let (Some((lo, hi)), false, false) = (range, excused, special) {
        if int < lo || int > hi {
            return Err(format!(
                "raw value {int} is outside the field's range {lo}..={hi}"
            ));
        }
    }
    match want {
        StatedValue::Exact { text, why } => match Rational::parse(text) {
            Ok(n) => compare(p, f, bits, raw, &StatedValue::Number(n), excused),
            Err(_) => Err(why.clone()),
        },
        StatedValue::Numbers(_) | StatedValue::Records(_) => {
            Err("not a repeated field; state one value".to_owned())
        }
        StatedValue::Number(n) => {
            let (got, sym) = match unit.map(|u| &p.units[u]) {
                Some(u) => (u.physical(int), u.symbol.as_str()),
                None => (Rational::int(i128::from(int)), ""),
            };
            if got == *n {
                Ok(())
            } else {
                Err(
                    format!("the frame carries {got} {sym} (raw {int}), the example states {n}")
                        .replace("  (", " ("),
                )
            }
        }
        StatedValue::Name(name) => {
            if let Some(e) = f.enumeration.map(|e| &p.enums[e]) {
                return match e.values.iter().find(|v| v.value as i64 == int) {
                    Some(v) if &v.name == name => Ok(()),
                    Some(v) => Err(format!(
                        "the frame carries {} ({int}), the example states {name}",
                        v.name
                    )),
                    None => Err(format!(
                        "the frame carries {int}, not a value of enum `{}`",
                        e.name
                    )),
                };
            }
            match f.special.iter().find(|s| s.value == int) {
                Some(s) if &s.name == name => Ok(()),
                Some(s) => Err(format!(
                    "the frame carries {} ({int}), the example states {name}",
                    s.name
                )),
                None => Err(format!(
                    "the example states `{name}`, but raw {int} is not a named value of this field"
                )),
            }
        }
        StatedValue::Names(names) => {
            let Some(fs) = f.flags.map(|x| &p.flags[x]) else {
                return Err("a list of names is only for flag fields".to_owned());
            };
            for n in names {
                if !fs.bits.iter().any(|b| &b.name == n) {
                    return Err(format!("`{n}` is not a flag of `{}`", fs.name));
                }
            }
            let set: BTreeSet<&str> = fs
                .bits
                .iter()
                .filter(|b| (int >> b.bit) & 1 == 1)
                .map(|b| b.name.as_str())
                .collect();
            let want: BTreeSet<&str> = names.iter().map(String::as_str).collect();
            let named: i64 = fs.bits.iter().map(|b| 1i64 << b.bit).sum();
            if set != want {
                Err(format!(
                    "the frame sets {:?}, the example states {:?}",
                    set, want
                ))
            } else if int & !named != 0 {
                Err(format!("the frame sets unnamed bits 0x{:X}", int & !named))
            } else {
                Ok(())
            }
        }
    }
}
