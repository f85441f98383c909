//! The spec's optional `transactions:` section: what a bus master needs beyond the codec.
//!
//! ```yaml
//! transactions:
//!   section: "serial 2.4.1"               # where the document says it (optional)
//!   response_timeout_ms: 1000             # how long a device may take to start its reply
//!   turnaround_ms: 100                    # a device's turnaround (before its reply, and after a broadcast)
//!   inter_frame_gap: {characters: 3.5, at_least_ms: 1.75}   # quiet time in character times
//!   retry:
//!     safe_kinds: [getter]                # kinds safe to send twice (default: getter, completion_check, setter)
//!     safe: [read_x]                      # commands safe although their kind is not
//!     unsafe: [get_status]                # commands not safe although their kind is
//! ```
//!
//! Every key is optional, and so is the section; absent, a master keeps its own defaults (a
//! reply timeout for the baud rate, no turnaround, the serial section's gap, retries by kind).
//! Whether a broadcast is answered stays each command's `broadcast`, and which replies are
//! refusals each response's `kind: nak`: the section does not say them again.
//!
//! The serial section's `inter_frame_gap_ms` is the gap at the document's baud rate;
//! `inter_frame_gap` says how it scales with the line's: `characters` character times (start,
//! data, parity and stop bits), never less than `at_least_ms`. Where a spec gives both, they
//! must agree at the document's baud rate (to the millisecond), so an old spec means what it
//! did and a new one cannot say two things.

use serde_derive::Deserialize;

use crate::diag::{join, Sink};
use crate::ir::MessageKind;
use crate::model::{CommandKind, NumberText, Parity};
use crate::rational::Rational;

/// The section as written.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Section {
    #[serde(default)]
    pub section: Option<String>,
    #[serde(default)]
    pub response_timeout_ms: Option<NumberText>,
    #[serde(default)]
    pub turnaround_ms: Option<NumberText>,
    #[serde(default)]
    pub inter_frame_gap: Option<GapSpec>,
    #[serde(default)]
    pub retry: Option<RetrySpec>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GapSpec {
    pub characters: NumberText,
    #[serde(default)]
    pub at_least_ms: Option<NumberText>,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RetrySpec {
    #[serde(default)]
    pub safe_kinds: Option<Vec<CommandKind>>,
    #[serde(default)]
    pub safe: Vec<String>,
    #[serde(default)]
    pub r#unsafe: Vec<String>,
}

/// The kinds a master may send twice when nothing else is said: reads, completion checks and
/// setters (the same value set twice is set once); never movements or resets.
pub const DEFAULT_SAFE_KINDS: [CommandKind; 3] = [
    CommandKind::Getter,
    CommandKind::CompletionCheck,
    CommandKind::Setter,
];

/// The longest timeout, turnaround or gap a spec may declare: one minute.
pub const MAX_MS: i128 = 60_000;
/// The most character times an inter-frame gap may last.
pub const MAX_CHARACTERS: i128 = 1_000;

/// A gap in character times, in tenths of a character, never shorter than `at_least_us`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CharacterGap {
    pub tenths: u32,
    pub at_least_us: u32,
}

/// The section, resolved (defaults filled in where the master's are the spec's).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transactions {
    /// The spec has the section.
    pub declared: bool,
    pub section: Option<String>,
    pub response_timeout_us: Option<u32>,
    pub turnaround_us: Option<u32>,
    pub gap: Option<CharacterGap>,
    /// Bits one character takes on the line: start, data, parity, stop.
    pub character_bits: u32,
    /// The kinds safe to send twice, in [`DEFAULT_SAFE_KINDS`]' order when not declared.
    pub safe_kinds: Vec<CommandKind>,
    /// Commands safe although their kind is not, in spec order of the list.
    pub safe: Vec<String>,
    /// Commands not safe although their kind is.
    pub not_safe: Vec<String>,
}

impl Transactions {
    /// What a spec without the section means.
    pub fn undeclared(character_bits: u32) -> Transactions {
        Transactions {
            declared: false,
            section: None,
            response_timeout_us: None,
            turnaround_us: None,
            gap: None,
            character_bits,
            safe_kinds: DEFAULT_SAFE_KINDS.to_vec(),
            safe: Vec::new(),
            not_safe: Vec::new(),
        }
    }

    /// Whether a master may send `command` again when its reply is lost or garbled.
    pub fn retry_safe(&self, command: &crate::ir::Message) -> bool {
        let MessageKind::Command(kind) = command.kind else {
            return false;
        };
        if self.not_safe.contains(&command.name) {
            return false;
        }
        self.safe.contains(&command.name) || self.safe_kinds.contains(&kind)
    }

    /// The inter-frame gap at `baud`, in microseconds (rounded up), if declared in characters.
    pub fn gap_us_at(&self, baud: u32) -> Option<u64> {
        let g = self.gap?;
        let bits = u64::from(g.tenths) * u64::from(self.character_bits);
        let us = (bits * 1_000_000).div_ceil(10 * u64::from(baud.max(1)));
        Some(us.max(u64::from(g.at_least_us)))
    }
}

/// Bits one character takes on a line of these settings.
pub fn character_bits(data_bits: u8, parity: Parity, stop_bits: u8) -> u32 {
    1 + u32::from(data_bits) + u32::from(parity != Parity::None) + u32::from(stop_bits)
}

/// A duration in milliseconds (`"1.75"`), as whole microseconds within `0..=MAX_MS`.
fn micros(n: &NumberText, path: &str, positive: bool, sink: &mut Sink) -> Option<u32> {
    let r = match Rational::parse(&n.0) {
        Ok(r) => r,
        Err(e) => {
            sink.error(path, e);
            return None;
        }
    };
    let us = r.times(Rational::int(1000));
    match us {
        Some(us) if !us.is_integer() => {
            sink.error(
                path,
                format!("{} ms is not a whole number of microseconds", n.0),
            );
            None
        }
        Some(us) if us.round() < 0 || (positive && us.round() == 0) => {
            let want = if positive { "positive" } else { "0 or more" };
            sink.error(path, format!("{} ms: must be {want}", n.0));
            None
        }
        Some(us) if us.round() > MAX_MS * 1000 => {
            sink.error(path, format!("{} ms is longer than {MAX_MS} ms", n.0));
            None
        }
        Some(us) => u32::try_from(us.round()).ok(),
        None => {
            sink.error(path, format!("{} ms is out of range", n.0));
            None
        }
    }
}

/// Validates the section against the spec's commands and serial line; errors located under
/// `transactions`.
pub fn validate(
    section: Option<&Section>,
    serial: &crate::model::Serial,
    commands: &[crate::model::Command],
    sink: &mut Sink,
) -> Transactions {
    let bits = character_bits(serial.data_bits, serial.parity, serial.stop_bits);
    let mut t = Transactions::undeclared(bits);
    let Some(s) = section else {
        return t;
    };
    let root = "transactions";
    t.declared = true;
    if let Some(sec) = &s.section {
        if sec.trim().is_empty() {
            sink.error(join(root, "section"), "section is empty");
        }
        t.section = Some(sec.clone());
    }
    if let Some(n) = &s.response_timeout_ms {
        t.response_timeout_us = micros(n, &join(root, "response_timeout_ms"), true, sink);
    }
    if let Some(n) = &s.turnaround_ms {
        t.turnaround_us = micros(n, &join(root, "turnaround_ms"), false, sink);
    }
    if let Some(g) = &s.inter_frame_gap {
        let gp = join(root, "inter_frame_gap");
        let cp = join(&gp, "characters");
        let tenths = match Rational::parse(&g.characters.0) {
            Err(e) => {
                sink.error(&cp, e);
                None
            }
            Ok(c) => match c.times(Rational::int(10)) {
                Some(x) if x.is_integer() && x.round() > 0 && x.round() <= MAX_CHARACTERS * 10 => {
                    u32::try_from(x.round()).ok()
                }
                Some(x) if x.is_integer() => {
                    sink.error(
                        &cp,
                        format!(
                            "{} character times: expected more than 0, at most {MAX_CHARACTERS}",
                            g.characters.0
                        ),
                    );
                    None
                }
                _ => {
                    sink.error(
                        &cp,
                        format!(
                            "{} character times: give tenths at most (3.5)",
                            g.characters.0
                        ),
                    );
                    None
                }
            },
        };
        let at_least = match &g.at_least_ms {
            Some(n) => micros(n, &join(&gp, "at_least_ms"), false, sink),
            None => Some(0),
        };
        if let (Some(tenths), Some(at_least_us)) = (tenths, at_least) {
            t.gap = Some(CharacterGap {
                tenths,
                at_least_us,
            });
            if let (Some(ms), Some(us)) = (serial.inter_frame_gap_ms, t.gap_us_at(serial.baud)) {
                // To the nearest millisecond, halves up.
                let at_baud = (us + 500) / 1000;
                if u64::from(ms) != at_baud {
                    sink.error(
                        &cp,
                        format!(
                            "{} character times at {} baud ({bits} bits each) are {}.{:03} ms, \
                             but serial.inter_frame_gap_ms says {ms} ms",
                            g.characters.0,
                            serial.baud,
                            us / 1000,
                            us % 1000
                        ),
                    );
                }
            }
        }
    }
    if let Some(r) = &s.retry {
        let rp = join(root, "retry");
        if let Some(kinds) = &r.safe_kinds {
            for (i, k) in kinds.iter().enumerate() {
                if kinds[..i].contains(k) {
                    sink.error(
                        join(&join(&rp, "safe_kinds"), &format!("[{i}]")),
                        format!("{} is listed twice", kind_name(*k)),
                    );
                }
            }
            t.safe_kinds = kinds.clone();
        }
        let lists = [("safe", &r.safe), ("unsafe", &r.r#unsafe)];
        for (key, list) in lists {
            for (i, name) in list.iter().enumerate() {
                let path = join(&join(&rp, key), &format!("[{i}]"));
                let Some(c) = commands.iter().find(|c| c.name == *name) else {
                    sink.error(path, format!("unknown command `{name}`"));
                    continue;
                };
                if list[..i].contains(name) {
                    sink.error(path, format!("`{name}` is listed twice"));
                    continue;
                }
                let by_kind = t.safe_kinds.contains(&c.kind);
                if key == "safe" && r.r#unsafe.contains(name) {
                    sink.error(path, format!("`{name}` is listed both safe and unsafe"));
                } else if (key == "safe") == by_kind {
                    sink.error(
                        path,
                        format!(
                            "`{name}` is a {} command, which is {} by its kind already",
                            kind_name(c.kind),
                            if by_kind { "safe" } else { "unsafe" }
                        ),
                    );
                }
            }
        }
        t.safe = r.safe.clone();
        t.not_safe = r.r#unsafe.clone();
    }
    t
}

/// A kind as the spec writes it.
pub fn kind_name(k: CommandKind) -> &'static str {
    match k {
        CommandKind::Movement => "movement",
        CommandKind::CompletionCheck => "completion_check",
        CommandKind::Setter => "setter",
        CommandKind::Getter => "getter",
        CommandKind::Reset => "reset",
    }
}

/// A duration in microseconds as milliseconds (`1.75 ms`).
pub fn ms_text(us: u32) -> String {
    if us % 1000 == 0 {
        format!("{} ms", us / 1000)
    } else {
        let s = format!("{}.{:03}", us / 1000, us % 1000);
        format!("{} ms", s.trim_end_matches('0'))
    }
}

/// A gap in tenths of a character as text (`3.5 character times`).
pub fn characters_text(tenths: u32) -> String {
    if tenths % 10 == 0 {
        format!("{} character times", tenths / 10)
    } else {
        format!("{}.{} character times", tenths / 10, tenths % 10)
    }
}

/// The Markdown the reference gives the section (empty for a spec without it).
#[cfg(feature = "tools")]
pub fn render(p: &crate::ir::Protocol) -> String {
    use std::fmt::Write;
    let t = &p.transactions;
    if !t.declared {
        return String::new();
    }
    let mut o = String::new();
    let _ = writeln!(
        o,
        "## Transactions{}\n",
        t.section
            .as_ref()
            .map(|x| format!(" (§{x})"))
            .unwrap_or_default()
    );
    if let Some(us) = t.response_timeout_us {
        let _ = writeln!(o, "- Response timeout: {}.", ms_text(us));
    }
    if let Some(us) = t.turnaround_us {
        let _ = writeln!(o, "- Turnaround: {}.", ms_text(us));
    }
    if let Some(g) = t.gap {
        let _ = write!(
            o,
            "- Inter-frame gap: {} ({} bits each)",
            characters_text(g.tenths),
            t.character_bits
        );
        if g.at_least_us > 0 {
            let _ = write!(o, ", at least {}", ms_text(g.at_least_us));
        }
        o.push_str(".\n");
    }
    let kinds: Vec<&str> = t.safe_kinds.iter().map(|k| kind_name(*k)).collect();
    let _ = writeln!(
        o,
        "- Safe to retry: {} commands{}{}.",
        if kinds.is_empty() {
            "no".to_owned()
        } else {
            kinds.join(", ")
        },
        names(" and ", &t.safe),
        names("; not ", &t.not_safe)
    );
    let unanswered = p
        .commands
        .iter()
        .filter(|c| {
            c.broadcast
                .as_ref()
                .is_some_and(|b| b.accepted && !b.answered)
        })
        .count();
    let refusals = p
        .responses
        .iter()
        .filter(|r| matches!(r.kind, MessageKind::Response(crate::ir::ResponseKind::Nak)))
        .count();
    let _ = writeln!(
        o,
        "- Broadcasts not answered: {unanswered} command(s); refusals (`kind: nak`): {refusals} response(s).\n"
    );
    o
}

#[cfg(feature = "tools")]
fn names(lead: &str, list: &[String]) -> String {
    if list.is_empty() {
        return String::new();
    }
    let l: Vec<String> = list.iter().map(|n| format!("`{n}`")).collect();
    format!("{lead}{}", l.join(", "))
}

/// One classified difference between two revisions' sections: `(breaks the wire, path, text)`.
/// A longer timeout, turnaround or gap, or a command no longer safe to retry, breaks a master
/// built on the old values; the rest is compatible.
#[cfg(feature = "tools")]
pub fn diff(old: &Transactions, new: &Transactions) -> Vec<(bool, String, String)> {
    let mut out = Vec::new();
    let show = |v: Option<u32>| v.map_or("not declared".to_owned(), ms_text);
    for (key, label, o, n) in [
        (
            "response_timeout_ms",
            "response timeout",
            old.response_timeout_us,
            new.response_timeout_us,
        ),
        (
            "turnaround_ms",
            "turnaround",
            old.turnaround_us,
            new.turnaround_us,
        ),
    ] {
        if o != n {
            out.push((
                n.unwrap_or(0) > o.unwrap_or(0),
                format!("transactions.{key}"),
                format!("{label}: {} → {}", show(o), show(n)),
            ));
        }
    }
    if old.gap != new.gap {
        let g = |g: Option<CharacterGap>| {
            g.map_or("not declared".to_owned(), |g| {
                format!(
                    "{}, at least {}",
                    characters_text(g.tenths),
                    ms_text(g.at_least_us)
                )
            })
        };
        let longer = |a: Option<CharacterGap>, b: Option<CharacterGap>| match (a, b) {
            (Some(a), Some(b)) => b.tenths > a.tenths || b.at_least_us > a.at_least_us,
            (None, Some(_)) => true,
            _ => false,
        };
        out.push((
            longer(old.gap, new.gap),
            "transactions.inter_frame_gap".to_owned(),
            format!("inter-frame gap: {} → {}", g(old.gap), g(new.gap)),
        ));
    }
    out
}

/// The commands whose retry safety changed between two revisions (commands in both):
/// `(command name, safe before, safe now)`.
#[cfg(feature = "tools")]
pub fn retry_changes(
    old: &crate::ir::Protocol,
    new: &crate::ir::Protocol,
) -> Vec<(String, bool, bool)> {
    new.commands
        .iter()
        .filter_map(|n| {
            let o = old.commands.iter().find(|o| o.name == n.name)?;
            let (a, b) = (
                old.transactions.retry_safe(o),
                new.transactions.retry_safe(n),
            );
            (a != b).then(|| (n.name.clone(), a, b))
        })
        .collect()
}
