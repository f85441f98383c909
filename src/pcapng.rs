//! pcapng out and in for `decode --stream`, over the `pcap-file` crate.
//!
//! Out ([`Writer`]): one Enhanced Packet Block per stream event, in capture order: every frame,
//! and also the bytes that start no frame (skipped, ambiguous, out of spec), so that the
//! packets concatenated are the capture byte for byte (a flag two frames share,
//! `ir::Framing::shared_flag`, is in the later frame's packet alone: the earlier frame's
//! packet lacks its closing flag, which the dissector puts back). The link type is `LINKTYPE_USER0`
//! (147): a packet's data is the frame's wire bytes and nothing else, where issue 25's
//! generated dissector registers. The one interface names the protocol in `if_description`
//! (`busspec PROTOCOL`) and the capture in `if_name`, its `if_speed` is the spec's baud rate.
//! A frame's direction is in `epb_flags` (bits 0–1: a request outbound, a response inbound,
//! as the host that polls sees them; 0 for bytes of no known direction); its comment says the
//! message, or why the bytes are not a frame. An offline capture has no time: a packet's
//! timestamp is the time its first byte starts after the capture's first byte, at the
//! spec's serial settings (start bit, data bits, parity, stop bits at the baud rate), from
//! the epoch, in nanoseconds (`if_tsresol` 9).
//!
//! The writer learns each event's offset, direction and message from the JSON line the stream
//! printed for it (the contract both engines print alike), so one path serves the generated
//! code and the interpreter, and the file cannot disagree with stdout. An event's bytes run to
//! the next event's offset (or the capture's end).
//!
//! In ([`read`]): the packets' bytes of every Enhanced, Simple and (obsolete) Packet Block,
//! concatenated in file order, are the capture; offsets in the events are offsets in that
//! concatenation (for a file [`Writer`] wrote, the original capture's). Only user link types
//! (147–162) are read: they carry bus bytes as they are; anything else is refused.

use std::borrow::Cow;
use std::io::{Read, Write};
use std::time::Duration;

use busspec_json::Spec;
use busspec_model::ir::Parity;
use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use pcap_file::pcapng::{Block, PcapNgParser, PcapNgWriter};
use pcap_file::{DataLink, PcapError};

/// The first four bytes of a pcapng file (a Section Header Block's type).
const SHB_TYPE: [u8; 4] = [0x0A, 0x0D, 0x0D, 0x0A];

/// `LINKTYPE_USER0`, the link type busspec writes.
pub const LINKTYPE: u32 = 147;

/// The user link types (`LINKTYPE_USER0..=LINKTYPE_USER15`), the ones [`read`] accepts.
const USER_LINKTYPES: std::ops::RangeInclusive<u32> = 147..=162;

/// `epb_flags` direction bits: inbound (a response), outbound (a request).
pub const INBOUND: u32 = 0b01;
pub const OUTBOUND: u32 = 0b10;

/// Whether `head` (a capture's first bytes, at least 12 where the capture has them) is a
/// pcapng file: a Section Header Block's type, then its byte-order magic in either order, so
/// that a raw capture merely starting with `0A 0D 0D 0A` is not taken for one.
pub fn is_pcapng(head: &[u8]) -> bool {
    head.len() >= 12
        && head[..4] == SHB_TYPE
        && matches!(
            head[8..12],
            [0x1A, 0x2B, 0x3C, 0x4D] | [0x4D, 0x3C, 0x2B, 0x1A]
        )
}

/// The bits one character takes on the line (start, data, parity, stop).
fn bits_per_char(spec: &Spec) -> u64 {
    let parity = match spec.serial.parity {
        Parity::None => 0,
        _ => 1,
    };
    1 + u64::from(spec.serial.data_bits) + parity + u64::from(spec.serial.stop_bits)
}

/// What the writer reads from a stream's JSON line.
#[derive(serde::Deserialize)]
struct Head {
    offset: u64,
    direction: Option<String>,
    message: Option<String>,
    skipped: Option<u64>,
    ambiguous: Option<Vec<String>>,
    out_of_spec: Option<String>,
    error: Option<String>,
    /// When the event's first byte started (`sniff`, a timed capture), in seconds.
    time: Option<Box<serde_json::value::RawValue>>,
}

/// An event whose bytes are not all known yet.
struct Pending {
    offset: u64,
    flags: u32,
    comment: String,
    /// Its line's `"time"`, in ns since the epoch.
    time_ns: Option<u64>,
}

/// Writes the events of one stream to a pcapng file.
pub struct Writer<W: Write> {
    out: PcapNgWriter<W>,
    /// Where the file goes, for errors.
    name: String,
    /// Bits per character and baud rate: the timestamps.
    bits: u64,
    baud: u64,
    /// The capture's bytes from offset `base` on, not yet written.
    bytes: Vec<u8>,
    base: u64,
    last: Option<Pending>,
}

/// A pcapng file at `path` for `spec`'s frames (see [`Writer::new`]), created now.
pub fn create(
    path: &std::path::Path,
    spec: &Spec,
    capture: &str,
    baud: u32,
) -> Result<Writer<std::io::BufWriter<std::fs::File>>, String> {
    let to = path.display().to_string();
    let f = std::fs::File::create(path).map_err(|e| format!("error: cannot write {to}: {e}"))?;
    Writer::new(std::io::BufWriter::new(f), &to, spec, capture, baud)
}

impl<W: Write> Writer<W> {
    /// A pcapng file of `spec`'s frames on `out` (called `name` in errors), the capture called
    /// `capture` in its interface's name, heard at `baud`. Writes the section header and the
    /// interface.
    pub fn new(out: W, name: &str, spec: &Spec, capture: &str, baud: u32) -> Result<Self, String> {
        let fail = |e: PcapError| format!("error: cannot write {name}: {e}");
        let mut out = PcapNgWriter::new(out).map_err(fail)?;
        let interface = InterfaceDescriptionBlock {
            linktype: DataLink::from(LINKTYPE),
            snaplen: 0,
            options: vec![
                InterfaceDescriptionOption::IfName(Cow::Owned(capture.to_owned())),
                InterfaceDescriptionOption::IfDescription(Cow::Owned(format!(
                    "busspec {}",
                    spec.name
                ))),
                InterfaceDescriptionOption::IfSpeed(u64::from(baud)),
                InterfaceDescriptionOption::IfTsResol(9),
            ],
        };
        out.write_pcapng_block(interface).map_err(fail)?;
        Ok(Writer {
            out,
            name: name.to_owned(),
            bits: bits_per_char(spec),
            baud: u64::from(baud).max(1),
            bytes: Vec::new(),
            base: 0,
            last: None,
        })
    }

    /// Takes the capture's next bytes (before the lines of the events they settle).
    pub fn bytes(&mut self, data: &[u8]) {
        self.bytes.extend_from_slice(data);
    }

    /// Takes the JSON lines the stream printed for the bytes given so far; writes every event
    /// whose end is known.
    pub fn lines(&mut self, lines: &[u8]) -> Result<(), String> {
        for line in lines.split(|&b| b == b'\n').filter(|l| !l.is_empty()) {
            let head: Head = serde_json::from_slice(line).map_err(|e| {
                format!(
                    "error: {}: a stream line is not an event ({e}): {}",
                    self.name,
                    String::from_utf8_lossy(line)
                )
            })?;
            self.write_to(head.offset)?;
            self.last = Some(pending(head));
        }
        Ok(())
    }

    /// Writes the last event, up to the capture's end; returns the output.
    pub fn finish(mut self) -> Result<W, String> {
        let end = self.base + self.bytes.len() as u64;
        self.write_to(end)?;
        let mut out = self.out.into_inner();
        out.flush()
            .map_err(|e| format!("error: cannot write {}: {e}", self.name))?;
        Ok(out)
    }

    /// Writes one packet: `data` at `timestamp` (since the epoch), direction `flags`
    /// ([`OUTBOUND`], [`INBOUND`] or 0), with `comment`.
    pub fn packet(
        &mut self,
        timestamp: Duration,
        data: &[u8],
        flags: u32,
        comment: String,
    ) -> Result<(), String> {
        let mut options = vec![EnhancedPacketOption::Comment(Cow::Owned(comment))];
        if flags != 0 {
            options.push(EnhancedPacketOption::Flags(flags));
        }
        let packet = EnhancedPacketBlock {
            interface_id: 0,
            timestamp,
            original_len: data.len() as u32,
            data: Cow::Borrowed(data),
            options,
        };
        self.out
            .write_pcapng_block(packet)
            .map_err(|e| format!("error: cannot write {}: {e}", self.name))?;
        Ok(())
    }

    /// Writes the pending event, whose bytes end at capture offset `end`.
    fn write_to(&mut self, end: u64) -> Result<(), String> {
        let Some(last) = self.last.take() else {
            return Ok(());
        };
        let known = self.base + self.bytes.len() as u64;
        if last.offset < self.base || end < last.offset || end > known {
            return Err(format!(
                "error: {}: event at offset {} ends at {end}, outside the bytes read ({}..{known})",
                self.name, last.offset, self.base
            ));
        }
        let from = (last.offset - self.base) as usize;
        let to = (end - self.base) as usize;
        if to > from {
            let nanos = match last.time_ns {
                Some(ns) => u128::from(ns),
                None => {
                    u128::from(last.offset) * u128::from(self.bits) * 1_000_000_000
                        / u128::from(self.baud)
                }
            };
            let timestamp = Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX));
            let data = std::mem::take(&mut self.bytes);
            let written = self.packet(timestamp, &data[from..to], last.flags, last.comment);
            self.bytes = data;
            written?;
        }
        self.bytes.drain(..to);
        self.base = end;
        Ok(())
    }
}

/// An event's flags and comment from its line.
fn pending(head: Head) -> Pending {
    let flags = match head.direction.as_deref() {
        Some("request") => OUTBOUND,
        Some("response") => INBOUND,
        _ => 0,
    };
    let comment = if let Some(reason) = head.out_of_spec {
        format!("out of spec: {reason}")
    } else if let Some(names) = head.ambiguous {
        format!("ambiguous: {}", names.join(" or "))
    } else if let Some(n) = head.skipped {
        format!("skipped: {n} bytes that start no frame")
    } else if let Some(why) = head.error {
        format!("error: {why}")
    } else {
        let direction = head.direction.unwrap_or_default();
        let message = head.message.unwrap_or_default();
        format!("{direction} {message}")
    };
    Pending {
        offset: head.offset,
        flags,
        comment,
        time_ns: head.time.as_deref().and_then(|t| seconds_ns(t.get())),
    }
}

/// A packet's timestamp in nanoseconds since the epoch. `pcap-file` hands the block's raw
/// 64-bit count over as nanoseconds whatever the interface's resolution; it is counted here in
/// units of `if_tsresol` (10^-6 s when absent, 2^-n s where the top bit is set), from
/// `if_tsoffset` seconds.
fn timestamp_ns(interface: &InterfaceDescriptionBlock, raw: Duration) -> u64 {
    let (mut resol, mut offset) = (6u8, 0u64);
    for o in &interface.options {
        match o {
            InterfaceDescriptionOption::IfTsResol(r) => resol = *r,
            InterfaceDescriptionOption::IfTsOffset(s) => offset = *s,
            _ => {}
        }
    }
    let ticks = raw.as_nanos();
    let ns = if resol & 0x80 == 0 {
        let exp = u32::from(resol.min(30));
        if exp <= 9 {
            ticks * 10u128.pow(9 - exp)
        } else {
            ticks / 10u128.pow(exp - 9)
        }
    } else {
        (ticks * 1_000_000_000) >> u32::from((resol & 0x7F).min(100))
    };
    let ns = ns.saturating_add(u128::from(offset) * 1_000_000_000);
    u64::try_from(ns).unwrap_or(u64::MAX)
}

/// `"1795660000.123456"` (seconds, up to nine decimals) as nanoseconds, exactly.
fn seconds_ns(text: &str) -> Option<u64> {
    let (secs, frac) = text.split_once('.').unwrap_or((text, ""));
    if frac.len() > 9 || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let secs: u64 = secs.parse().ok()?;
    let frac: u64 = if frac.is_empty() {
        0
    } else {
        frac.parse::<u64>().ok()? * 10u64.pow(9 - frac.len() as u32)
    };
    secs.checked_mul(1_000_000_000)?.checked_add(frac)
}

/// Reads a pcapng file from `input` (called `name`), whose first bytes `head` were already
/// read, and gives each packet's bytes to `packet`, in file order, with its timestamp in
/// nanoseconds since the epoch (its interface's `if_tsresol` and `if_tsoffset` applied; `None`
/// for a Simple Packet Block, which has none). An error names the block (counted from 0) and
/// the byte offset in the file where it starts.
pub fn read(
    name: &str,
    head: Vec<u8>,
    input: &mut dyn Read,
    mut packet: impl FnMut(&[u8], Option<u64>) -> Result<(), String>,
) -> Result<(), String> {
    let mut buf = head;
    // `buf[0]` is at file offset `at`; `buf[pos..]` not parsed yet.
    let (mut at, mut pos) = (0u64, 0usize);
    let mut eof = false;
    let mut parser: Option<PcapNgParser> = None;
    let mut block = 0u64;
    let mut chunk = vec![0u8; 64 * 1024];
    loop {
        if eof && pos == buf.len() && parser.is_some() {
            return Ok(());
        }
        let where_ = |at: u64, pos: usize| {
            format!(
                "error: pcapng {name}: block {block} at byte {}",
                at + pos as u64
            )
        };
        let mut fresh = None;
        let parsed = match parser.as_mut() {
            None => PcapNgParser::new(&buf[pos..]).map(|(rest, p)| {
                fresh = Some(p);
                (rest.len(), None)
            }),
            Some(p) => p
                .next_block(&buf[pos..])
                .map(|(rest, b)| (rest.len(), Some(b))),
        };
        if fresh.is_some() {
            parser = fresh;
        }
        match parsed {
            Ok((rest, b)) => {
                if let (Some(b), Some(p)) = (b, parser.as_ref()) {
                    let data = match &b {
                        Block::InterfaceDescription(i) => {
                            let linktype = u32::from(i.linktype);
                            if !USER_LINKTYPES.contains(&linktype) {
                                return Err(format!(
                                    "{}: interface {} has link type {linktype} ({:?}), not a user link type (147..=162) that carries bus bytes",
                                    where_(at, pos),
                                    p.interfaces().len().saturating_sub(1),
                                    i.linktype
                                ));
                            }
                            None
                        }
                        Block::EnhancedPacket(e) => {
                            if p.packet_interface(e).is_none() {
                                return Err(format!(
                                    "{}: packet of interface {}, which no interface block before it describes",
                                    where_(at, pos),
                                    e.interface_id
                                ));
                            }
                            let interface = p.packet_interface(e);
                            Some((&e.data, interface.map(|i| timestamp_ns(i, e.timestamp))))
                        }
                        Block::SimplePacket(s) => Some((&s.data, None)),
                        Block::Packet(s) => Some((&s.data, None)),
                        _ => None,
                    };
                    if let Some((data, time)) = data {
                        packet(data, time)?;
                    }
                }
                block += 1;
                pos = buf.len() - rest;
            }
            Err(PcapError::IncompleteBuffer) if !eof => {
                buf.drain(..pos);
                at += pos as u64;
                pos = 0;
                let n = loop {
                    match input.read(&mut chunk) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        Err(e) => {
                            return Err(format!(
                                "error: cannot read {name} (after {} bytes): {e}",
                                at + buf.len() as u64
                            ))
                        }
                    }
                };
                eof = n == 0;
                buf.extend_from_slice(&chunk[..n]);
            }
            Err(PcapError::IncompleteBuffer) => {
                return Err(format!(
                    "{}: truncated: the file ends {} bytes into it",
                    where_(at, pos),
                    buf.len() - pos
                ))
            }
            Err(e) => return Err(format!("{}: {e}", where_(at, pos))),
        }
    }
}
