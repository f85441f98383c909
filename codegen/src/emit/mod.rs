//! Emits the typed `no_std` Rust module of one protocol from its IR.
//!
//! One `emit_*` function per generated item, iterating in spec order so the output is
//! deterministic. Output is formatted with prettyplease. One file per generated item:
//! - `head`: the module head (docs, `SPEC_YAML`, buffer sizes, framing, checksum and escaping
//!   constants);
//! - `types`: units, enums and flags;
//! - `messages`: one struct per message in its direction's module (`request::ReadCoils`: its
//!   fields, `NAME`, `CODE`, `LEN` or `MIN_LEN`/`MAX_LEN`, the byte range of each field at a
//!   fixed offset, a typed constant per special value, `visit`, `encode`), the
//!   `Request`/`Response` enums holding them (a variant
//!   per message, `Request::ReadCoils(request::ReadCoils)`) and their per-message tables;
//!   `encode` and `decode` the arms of one message; `lists` where repeated fields sit and how
//!   they are split; `records` the struct of each repeated record;
//! - `dispatch`: code → message, the decode entry point;
//! - `stream`: the stream decoder's tables (`rt::Framing`);
//! - `protocol`: the `Protocol` impl, what the message types say beyond their frames
//!   (`rt::RequestMessage`, `rt::ResponseMessage`) and pairing (`COMMANDS`, `follows_request`);
//! - `view`: the borrowed views (`RequestView<'a>`/`ResponseView<'a>`: the decoders again,
//!   each list lent as `rt::ListView`/`rt::BitsView`), where `view::no_view` finds none missing;
//! - `desc`: each message struct's `impl` with its descriptors (`DESC`, the `rt::MessageDesc`
//!   of the message; `QUANTITY_DESC`, the `rt::FieldDesc` of each field a refusal names;
//!   `QUANTITY_CHECK`, the `rt::FieldCheck` of each field whose range or relation is checked:
//!   offset, range, rule), which the refusals point at and the checks take, and the `request`
//!   and `response` modules with the structs;
//! - `ctx` and `tokens`: what the others share (the IR walked as leaves, typed literals, docs).
//!
//! Shape (kept lean so a firmware engineer can read it):
//! - each module imports `::busspec_runtime::codec as rt` once and names everything from core
//!   and the runtime through it (`rt::Some`, `rt::Result`, `rt::DecodeError`): a lowercase
//!   module name no spec name can take, since spec names become `CamelCase` types, variants
//!   or fields (`codegen/tests/fixtures/core_names.yaml` names its types `Option`, `Ok`, ...);
//! - checks every frame or message shares are small `#[inline]` runtime helpers
//!   (`rt::FrameChecks`, `rt::in_range`, `rt::frame_mut`, `rt::Group`, ...), which take what
//!   they check from named constants (`rt::in_range(&Self::QUANTITY_CHECK, w_quantity)`,
//!   `FRAME.no_broadcast(frame[0], &Self::DESC)`) rather than positional numbers;
//! - per-message constants are tables (`MESSAGES`: name, code, length; `COMMANDS`: kind,
//!   broadcast rule, replies), indexed by one `match` (`index`);
//! - `dispatch` has one arm per code; a message with anything to check or read is decoded
//!   by its struct's own `from_frame` (`request::ReadCoils::from_frame(frame)
//!   .map(Self::ReadCoils)`: its length, or a variable-length frame split into its fixed part
//!   and lists, then each field's rule, naming its descriptors through `Self`), a fixed-length
//!   one without by the arm itself (a group's variable-length members by closures in it);
//!   the wire values it binds are named after their fields (`w_quantity`); codes, start bytes
//!   and addresses are written in hex as the documents print them;
//! - encode writes the bytes known before any field in one `copy_from_slice`, and keeps a sum-8
//!   in each arm, where it folds the constant header bytes; a message with fields is written
//!   by its struct's own `write` (`Self::ReadCoils(ref m) => m.write(address, buf)?`), one
//!   without (or without a checksum) in the arm.
//! - sized for `opt-level = "s"` as well as for speed (BENCHMARKS.md, "What the benches taught
//!   the generator"; the rounds in its history): no range check that cannot fail, one buffer
//!   check per `encode` where a direction has one frame length (it then precedes the message's
//!   own checks), a sum-8 arm's constant head summed here, and, where every reply code of a
//!   direction has one length, a refused reply's code written once by `decode`
//!   (`rt::reply_of`/`rt::reply_code`).
//!
//! Typing rules:
//! - a unit with scale 1 and offset 0 stays a plain integer of its field's width;
//! - any other unit becomes a newtype over the smallest integer that holds every field using it,
//!   with conversions to and from physical values;
//! - enums are open (`Unknown(raw)`), flags are a bit-set newtype, ascii fields `rt::Ascii<N>` (the bytes, shown as text);
//! - constants (and a list's count field, computed from the list) are not part of the typed
//!   message: encode writes them, decode checks them; a repeated field is an
//!   `rt::Repeated<wire, max>` or `rt::Bits<bytes>` value, with a `REPEAT_<NAME>` const saying
//!   where it sits and how it is counted; a repeated record is an `rt::Repeated<Struct, max>` of
//!   a struct named by its message and field, its fields typed by these rules;
//! - an optional field (`present:`) is an `rt::Option` of its type, with an `OPTIONAL_<NAME>`
//!   const (`rt::Optionals`) saying what each condition reads: decode lays the frame out as if
//!   every optional field were present and reads each at a fixed offset, encode writes that
//!   layout and packs the fields given into the frame.

mod ctx;
mod decode;
mod desc;
mod dispatch;
mod encode;
mod head;
mod lists;
mod messages;
mod protocol;
mod records;
mod stream;
#[cfg(test)]
mod tests;
mod tokens;
mod types;
mod view;

use ctx::*;
use ctx::{Kind, Leaf};
use decode::*;
use desc::*;
use dispatch::*;
use encode::*;
use head::*;
use lists::*;
use messages::*;
use protocol::*;
use records::*;
use stream::*;
pub use tokens::camel;
use tokens::*;
use types::*;
use view::*;

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote, ToTokens};

use busspec_model::interp::raw_limits;
use busspec_model::ir::*;
use busspec_model::rational::Rational;

/// The generated file's first line.
pub const PREAMBLE: &str =
    "// @generated by busspec-codegen from the spec; do not edit: edit the spec and rebuild.";

/// Emits the whole module for one protocol, formatted.
///
/// `source` names the spec in the module's documentation (`spec/ub2.yaml`); `spec_path` is the
/// path `include_str!` takes the spec's text from for `SPEC_YAML` (absolute, or relative to
/// the file the module is written to).
pub fn emit_module(p: &Protocol, source: &str, spec_path: &str) -> Result<String, String> {
    let gaps = p.generator_gaps();
    if !gaps.is_empty() {
        return Err(format!(
            "{}: the code generator cannot emit yet: {} (decode it with the interpreter: `busspec decode --spec`)",
            p.name,
            gaps.join("; ")
        ));
    }
    record_names(p)?;
    view_names(p)?;
    // A command's replies are a bit set of responses (`Request::COMMANDS`).
    if p.responses.len() > 128 {
        return Err(format!(
            "{} has {} responses; the generated code handles at most 128",
            p.name,
            p.responses.len()
        ));
    }
    let tokens = module_tokens(p, source, spec_path);
    let file: syn::File = syn::parse2(tokens)
        .map_err(|e| format!("generated code for {} does not parse: {e}", p.name))?;
    Ok(format!("{PREAMBLE}\n{}", prettyplease::unparse(&file)))
}

/// A repeated record's struct is named after its message and field (`SyncWriteBlocks`): that
/// name must be no other type's of the module (a unit's, an enum's, a flag set's, another
/// record's, or one the module always defines).
fn record_names(p: &Protocol) -> Result<(), String> {
    let mut taken: Vec<(String, String)> =
        ["Request", "Response", "Decoded", "StreamDecoder", "Event"]
            .iter()
            .map(|n| {
                (
                    n.to_string(),
                    "a type every generated module defines".to_owned(),
                )
            })
            .collect();
    taken.push((camel(&p.name), "the protocol's type".to_owned()));
    for (names, what) in [
        (p.units.iter().map(|u| &u.name).collect::<Vec<_>>(), "unit"),
        (p.enums.iter().map(|e| &e.name).collect(), "enum"),
        (p.flags.iter().map(|f| &f.name).collect(), "flag set"),
    ] {
        for n in names {
            taken.push((camel(n), format!("the {what} `{n}`")));
        }
    }
    for m in p.commands.iter().chain(&p.responses) {
        for f in m.fields.iter().filter(|f| f.is_record()) {
            let name = record_type(&m.name, f).to_string();
            if let Some((_, other)) = taken.iter().find(|(n, _)| *n == name) {
                return Err(format!(
                    "{}: the record `{}.{}` would be the struct `{name}`, the name of {other}; rename one (the interpreter serves it: `busspec decode --spec`)",
                    p.name, m.name, f.name
                ));
            }
            taken.push((name, format!("the record `{}.{}`", m.name, f.name)));
        }
    }
    Ok(())
}

fn module_tokens(p: &Protocol, source: &str, spec_path: &str) -> TokenStream {
    let ctx = Ctx::new(p);
    let header = emit_header(p, source, spec_path);
    let units = emit_units(&ctx);
    let enums = emit_enums(&ctx);
    let flags = emit_flags(&ctx);
    let checksum = emit_checksum(p);
    let frame_sums = emit_frame_sums(p);
    let frame_checks = dispatch::emit_frame_checks(p);
    let over_request = emit_over_request(p);
    let unchecked = emit_unchecked(p);
    let requests = emit_messages(&ctx, Direction::Request);
    let responses = emit_messages(&ctx, Direction::Response);
    let pairing = emit_pairing(&ctx);
    let request_view = emit_view(&ctx, Direction::Request);
    let response_view = emit_view(&ctx, Direction::Response);
    let stream = emit_stream(p);
    let descs = emit_descs(&ctx);
    let codes = code_consts(&ctx);
    let name = ident(&p.name);
    quote! {
      pub mod #name {
        #header
        #codes
        #checksum
        #frame_sums
        #frame_checks
        #over_request
        #unchecked
        #units
        #enums
        #flags
        #requests
        #responses
        #pairing
        #request_view
        #response_view
        #stream
        #descs
      }
    }
}
