//! Decoding one frame for printing, with either engine: errors that say what and where, and an
//! ambiguity that says how to settle it.

use busspec_model::interp::{self, DecodeError as InterpError, Frame};
use busspec_model::ir::Direction;
use busspec_runtime::{DecodeError, Decoded, FieldValue, Message, Protocol, ResponseMessage};

use crate::{Spec, Typed};

/// The commands whose request would settle an ambiguous frame.
fn settling_requests(p: &Spec, candidates: &[String]) -> Vec<String> {
    let mut names = Vec::new();
    for c in &p.commands {
        let answers = c.responses.iter().any(|(i, _)| {
            p.responses
                .get(*i)
                .is_some_and(|r| candidates.contains(&r.name))
        });
        if answers {
            names.push(c.name.clone());
        }
    }
    names
}

/// The error of a frame that could be any of `candidates`, given `--reply-to` or not.
fn ambiguous(p: &Spec, candidates: &[String], reply_to: Option<usize>) -> String {
    let listed = candidates.join(" or ");
    let is_request = |n: &String| p.commands.iter().any(|c| &c.name == n);
    if reply_to.is_none() && candidates.iter().any(is_request) && !candidates.iter().all(is_request)
    {
        // A request and a reply with the same bytes (a Modbus echo, a Dynamixel status packet
        // that reads like an instruction): the direction settles it.
        return format!(
            "ambiguous frame: could be {listed}; a request and a response look alike here: give --direction request or --direction response"
        );
    }
    match reply_to {
        None => {
            let requests = settling_requests(p, candidates);
            format!(
                "ambiguous frame: could be {listed}; only the request it answers tells them apart: give --reply-to {}",
                if requests.is_empty() {
                    "<command>".to_owned()
                } else {
                    requests.join(" or --reply-to ")
                }
            )
        }
        Some(cmd) => {
            let name = p.commands.get(cmd).map(|c| c.name.as_str()).unwrap_or("?");
            format!("ambiguous frame: could be {listed}, and {name} (--reply-to) gets none of them")
        }
    }
}

/// Decodes one frame with the interpreter: like [`interp::decode`], but an ambiguity says how
/// to settle it, and a `reply_to` (a command index) that settles nothing says so.
pub fn decode_frame<'p>(
    p: &'p Spec,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    wire: &[u8],
) -> Result<Frame<'p>, String> {
    decode_frame_with(p, direction, reply_to, None, wire)
}

/// [`decode_frame`] with the bytes the request's checksum covers (`covered`), which the
/// checksum of a reply that takes in its request's bytes runs over first
/// (`checksum_over_request`).
pub fn decode_frame_with<'p>(
    p: &'p Spec,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    covered: Option<&[u8]>,
    wire: &[u8],
) -> Result<Frame<'p>, String> {
    match interp::decode_with(p, direction, None, covered, wire) {
        Ok(f) => Ok(f),
        Err(InterpError::Ambiguous { candidates }) => match reply_to {
            None => Err(ambiguous(p, &candidates, None)),
            Some(cmd) => interp::decode_with(p, direction, Some(cmd), covered, wire)
                .map_err(|_| ambiguous(p, &candidates, Some(cmd))),
        },
        Err(e) => Err(e.to_string()),
    }
}

/// A frame that decodes as the request `d`, no direction given: the request, unless it is a
/// response too (a Modbus echo such as write_single_coil); then, as [`decode_frame`] says it,
/// the reply to `reply_to` where that command gets one of those responses, else ambiguous
/// between the request and the responses.
fn request_or_both<P: Protocol>(
    p: &Spec,
    reply_to: Option<usize>,
    wire: &[u8],
    d: Decoded<P::Request>,
) -> Result<Typed<P>, String> {
    let Some(responses) = responses_of::<P>(p, wire) else {
        return Ok(Typed::Request(d));
    };
    let settled = reply_to
        .and_then(|cmd| request_for_reply::<P>(p, cmd, wire))
        .and_then(|q| P::decode_reply(wire, &q).ok());
    if let Some(r) = settled {
        return Ok(Typed::Response(r));
    }
    let mut names = vec![d.message.name().to_owned()];
    names.extend(responses);
    Err(ambiguous(p, &names, reply_to))
}

/// Text to fill an ASCII field of a neutral request (widths are at most 255).
const SPACES: [u8; 255] = [b' '; 255];

/// A request of command `cmd` (an index into the spec's commands) of generated protocol `P`,
/// for the JSON contract's places that name a command without its values (`--reply-to`, a
/// stream's default request, the candidates of an ambiguous frame): what a response decoder
/// needs to know which request a response answers, which only the command decides. Built with
/// [`Message::from_fields`] from neutral values: enums at their first listed value, text all
/// spaces, every other field 0 (constants and repeated fields as the spec fixes them). `None`
/// if `P` has no such command.
pub fn request_for<P: Protocol>(p: &Spec, cmd: usize) -> Option<P::Request> {
    request_with::<P>(p, cmd, &[])
}

/// [`request_for`] as the request `wire` (a response) answers: a field a response takes from
/// the request (`follows: {request}`, a list counted by the request) holds what the frame's
/// value implies (a READ whose reply holds four bytes asked for four), as the interpreter
/// settles a reply by its command alone; every other field neutral.
pub(crate) fn request_for_reply<P: Protocol>(
    p: &Spec,
    cmd: usize,
    wire: &[u8],
) -> Option<P::Request> {
    let mut implied: Vec<(String, i64)> = Vec::new();
    if let Ok(f) = interp::decode(p, Some(Direction::Response), Some(cmd), wire) {
        let m = p.message(f.message);
        for field in &m.fields {
            let rel = match (&field.follows, &field.repeat) {
                (Some(busspec_model::ir::Follows::Request(rel)), _) => rel,
                (_, Some(r)) => match &r.request {
                    Some(rel) => rel,
                    None => continue,
                },
                _ => continue,
            };
            let n = match f.get(&field.name) {
                Some(interp::Raw::Int(v)) => *v,
                Some(raw) => raw.elements().map_or(0, |n| n as i64),
                None => continue,
            };
            // The request's value that gives `n`: its inverse, tried with its neighbours.
            let guess = n.saturating_mul(rel.divide as i64) / (rel.multiply as i64).max(1);
            if let Some(v) = (guess.saturating_sub(1)..=guess.saturating_add(1))
                .find(|v| *v >= 0 && rel.apply(*v) == n)
            {
                implied.push((rel.field.clone(), v));
            }
        }
    }
    request_with::<P>(p, cmd, &implied)
}

/// A request of command `cmd` from neutral values, but the named ones given.
fn request_with<P: Protocol>(p: &Spec, cmd: usize, given: &[(String, i64)]) -> Option<P::Request> {
    let c = p.commands.get(cmd)?;
    let neutral = |name: &'static str| {
        if let Some((_, v)) = given.iter().find(|(n, _)| n == name) {
            return Some(FieldValue::Int(*v));
        }
        let (f, bit) = interp::leaf_field(c, name)?;
        Some(match bit {
            Some(_) => FieldValue::Int(0),
            None if f.is_ascii() => FieldValue::Text(SPACES.get(..f.width)?),
            // A list or records: none (a reply is told apart by its command, not by them).
            None if f.is_record() => FieldValue::Records(busspec_runtime::RecordList::Flat {
                values: &[],
                fields: f.record.len().max(1),
            }),
            None if f.is_list() => FieldValue::List(busspec_runtime::Elements::I64(&[])),
            None => FieldValue::Int(
                f.enumeration
                    .and_then(|e| p.enums.get(e))
                    .and_then(|e| e.values.first())
                    .map_or(0, |v| v.value as i64),
            ),
        })
    };
    P::Request::from_fields(&c.name, neutral).ok()
}

/// The responses of `P` a frame decodes as, given some request: the candidates of an
/// ambiguous frame, in spec order.
pub(crate) fn candidates<P: Protocol>(p: &Spec, wire: &[u8]) -> Vec<String> {
    let mut found: Vec<&'static str> = Vec::new();
    for cmd in 0..p.commands.len() {
        if let Some(q) = request_for_reply::<P>(p, cmd, wire) {
            if let Ok(d) = P::decode_reply(wire, &q) {
                found.push(d.message.name());
            }
        }
    }
    p.responses
        .iter()
        .filter(|r| found.contains(&r.name.as_str()))
        .map(|r| r.name.clone())
        .collect()
}

/// The messages of `P` an ambiguous frame could be, as the interpreter lists them: the
/// request it decodes as (unless `direction` says it is a response: a Modbus echo reads both
/// ways), then the response it decodes as, or those of [`candidates`] where only a request
/// tells them apart.
pub(crate) fn ambiguous_candidates<P: Protocol>(
    p: &Spec,
    direction: Option<Direction>,
    wire: &[u8],
) -> Vec<String> {
    let request = match direction {
        Some(Direction::Response) => None,
        _ => P::decode_request(wire).ok(),
    };
    let mut names: Vec<String> = request
        .map(|d| d.message.name().to_owned())
        .into_iter()
        .collect();
    if direction != Some(Direction::Request) {
        names.extend(responses_of::<P>(p, wire).unwrap_or_default());
    }
    names
}

/// The responses of `P` a frame decodes as without its request: the one it is, those of
/// [`candidates`] where only a request tells them apart, or `None` when it is none.
fn responses_of<P: Protocol>(p: &Spec, wire: &[u8]) -> Option<Vec<String>> {
    match P::decode_response(wire) {
        Ok(r) => Some(vec![r.message.name().to_owned()]),
        Err(DecodeError::Ambiguous { .. }) => Some(candidates::<P>(p, wire)),
        Err(_) => None,
    }
}

/// The error of a frame that is neither a request nor a response.
fn either(request: DecodeError, response: DecodeError) -> DecodeError {
    match (request, response) {
        (
            DecodeError::Truncated {
                needed: a,
                found: n,
            },
            DecodeError::Truncated { needed: b, .. },
        ) => DecodeError::Truncated {
            needed: a.min(b),
            found: n,
        },
        (q, r) if r.progress() > q.progress() => r,
        (q, _) => q,
    }
}

/// Decodes one frame with generated protocol `P` (`p` its spec, from [`crate::load_spec`]):
/// as a request or a response (`direction`, or whichever it is), a response that only its
/// request tells apart as the reply to command `reply_to` (an index into the spec's commands).
/// Errors as [`decode_frame`] gives them.
pub fn decode_typed<P: Protocol>(
    p: &Spec,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    wire: &[u8],
) -> Result<Typed<P>, String> {
    decode_typed_with::<P>(p, direction, reply_to, None, wire)
}

/// [`decode_typed`] with the bytes the request's checksum covers (`covered`), which the
/// checksum of a reply that takes in its request's bytes runs over first
/// (`checksum_over_request`).
pub fn decode_typed_with<P: Protocol>(
    p: &Spec,
    direction: Option<Direction>,
    reply_to: Option<usize>,
    covered: Option<&[u8]>,
    wire: &[u8],
) -> Result<Typed<P>, String> {
    let request = match direction {
        Some(Direction::Response) => None,
        _ => match P::decode_request(wire) {
            Ok(d) if direction.is_some() => return Ok(Typed::Request(d)),
            Ok(d) => return request_or_both::<P>(p, reply_to, wire, d),
            Err(e) => Some(e),
        },
    };
    if direction == Some(Direction::Request) {
        return Err(request.map(|e| e.to_string()).unwrap_or_default());
    }
    let response = match P::Response::decode_as_reply_over(wire, None, covered) {
        Ok(d) => return Ok(Typed::Response(d)),
        Err(DecodeError::Ambiguous { .. }) => {
            let names = candidates::<P>(p, wire);
            let settled = reply_to
                .and_then(|cmd| request_for_reply::<P>(p, cmd, wire))
                .and_then(|q| P::decode_reply(wire, &q).ok());
            return match settled {
                Some(d) => Ok(Typed::Response(d)),
                None => Err(ambiguous(p, &names, reply_to)),
            };
        }
        Err(e) => e,
    };
    let e = match request {
        Some(q) => either(q, response),
        None => response,
    };
    Err(e.to_string())
}
