//! Framing by silence: a stream's events, with the time each started, closed by the line's
//! quiet as well as by its bytes (`sniff`, and `decode --stream` of a pcapng capture).
//!
//! The bytes arrive in chunks, each with the time its last byte ended (a read from a port, a
//! pcapng packet). A chunk of `n` bytes started `n` character times before that (start, data,
//! parity and stop bits at the line's baud rate), and never before the chunk before it ended.
//! The silence before a chunk is the time from the previous chunk's end to this one's start.
//!
//! Where the spec declares an inter-frame gap (its `transactions.inter_frame_gap` at the line's
//! baud rate, or else its serial section's `inter_frame_gap_ms`), a silence at least that long
//! closes whatever is open: the stream decoder settles what it holds, as at the end of a
//! capture (`finish`), and goes on with the next bytes, its pairing of replies to requests
//! kept. A live line closes the same way when no byte comes for a gap ([`Timed::idle`]), so a
//! frame prints as soon as the line has been quiet for a gap, not when the next one starts.
//!
//! Each event's line gains two keys after `"offset"`: `"time"`, when its first byte started,
//! in seconds since the Unix epoch with six decimals, and, where gap framing is on,
//! `"decided_by"`, what settled it:
//!
//! - `"bytes"`: the byte rule (the stream decoder's, as without timing) settled it before any
//!   gap, and bytes followed it with no gap between;
//! - `"timing"`: the byte rule still waited (a longer frame could start there, or its length
//!   had not arrived) when a gap closed it;
//! - `"both"`: the byte rule settled it, and a gap followed its last byte.
//!
//! The end of a capture settles what is left as bytes do, without a gap: `"bytes"`.
//!
//! Events are written in offset order. A `"bytes"` or `"both"` event is known only when the
//! next byte or the next gap comes, so the last frame settled by bytes waits for one of them.

use crate::frames::LineStream;

/// What settled an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decided {
    Bytes,
    Timing,
    Both,
}

impl Decided {
    fn name(self) -> &'static str {
        match self {
            Decided::Bytes => "bytes",
            Decided::Timing => "timing",
            Decided::Both => "both",
        }
    }
}

/// Nanoseconds one character takes at `baud` with `bits` bits per character.
pub fn char_ns(bits: u32, baud: u32) -> u64 {
    (u64::from(bits) * 1_000_000_000).div_ceil(u64::from(baud.max(1)))
}

/// The inter-frame gap of `spec` at `baud`, in nanoseconds: `transactions.inter_frame_gap` at
/// that rate, else the serial section's `inter_frame_gap_ms`; `None` where it declares neither.
pub fn spec_gap_ns(spec: &busspec_json::Spec, baud: u32) -> Option<u64> {
    spec.transactions
        .gap_us_at(baud)
        .or_else(|| {
            spec.serial
                .inter_frame_gap_ms
                .map(|ms| u64::from(ms) * 1000)
        })
        .map(|us| us * 1000)
}

/// Bytes received, by offset, with when they arrived: what the events' times come from.
#[derive(Debug, Clone, Copy)]
struct Chunk {
    offset: u64,
    /// When its first byte started (ns since the epoch).
    start_ns: u64,
}

/// A stream decoder's lines, timed and closed by silence (module docs).
pub struct Timed<'a> {
    stream: Box<dyn LineStream + 'a>,
    /// The inter-frame gap; `None`: no gap framing (lines get their time only).
    gap_ns: Option<u64>,
    char_ns: u64,
    /// Bytes pushed so far.
    pushed: u64,
    /// When the last byte pushed ended.
    last_end_ns: Option<u64>,
    /// A gap closed the stream since the last byte.
    closed: bool,
    chunks: std::collections::VecDeque<Chunk>,
    /// The last line the byte rule settled, with its time, waiting to learn whether a gap
    /// follows it.
    held: Option<(Vec<u8>, u64)>,
    scratch: Vec<u8>,
}

impl<'a> Timed<'a> {
    /// Times `stream`'s lines at `char_ns` per character, closing on silences of `gap_ns`.
    pub fn new(stream: Box<dyn LineStream + 'a>, char_ns: u64, gap_ns: Option<u64>) -> Self {
        Timed {
            stream,
            gap_ns: gap_ns.filter(|&g| g > 0),
            char_ns,
            pushed: 0,
            last_end_ns: None,
            closed: false,
            chunks: std::collections::VecDeque::new(),
            held: None,
            scratch: Vec::new(),
        }
    }

    /// Bytes pushed so far.
    pub fn pushed(&self) -> u64 {
        self.pushed
    }

    /// Feeds `data`, whose last byte ended at `end_ns` (ns since the epoch); writes the lines
    /// of the events settled so far to `out`.
    pub fn push(&mut self, data: &[u8], end_ns: u64, out: &mut Vec<u8>) {
        if data.is_empty() {
            return;
        }
        let len = data.len() as u64;
        let start = end_ns.saturating_sub(len.saturating_mul(self.char_ns));
        if let (Some(gap), Some(last)) = (self.gap_ns, self.last_end_ns) {
            if start.saturating_sub(last) >= gap {
                self.close(out);
            }
        }
        let start_ns = self.last_end_ns.map_or(start, |last| start.max(last));
        self.chunks.push_back(Chunk {
            offset: self.pushed,
            start_ns,
        });
        self.pushed += len;
        self.last_end_ns = Some(end_ns.max(start_ns));
        self.closed = false;
        let mut lines = std::mem::take(&mut self.scratch);
        lines.clear();
        self.stream.push(data, &mut lines);
        for line in split(&lines) {
            let time = self.time_of(line);
            if self.gap_ns.is_none() {
                self.write(line, time, None, out);
                continue;
            }
            if let Some((held, t)) = self.held.take() {
                self.write(&held, t, Some(Decided::Bytes), out);
            }
            self.held = Some((line.to_vec(), time));
        }
        self.scratch = lines;
    }

    /// Feeds `data` that came with no time of its own: right after the bytes before it.
    pub fn push_following(&mut self, data: &[u8], out: &mut Vec<u8>) {
        let len = data.len() as u64;
        let end = self
            .last_end_ns
            .unwrap_or(0)
            .saturating_add(len.saturating_mul(self.char_ns));
        self.push(data, end, out);
    }

    /// The line has been quiet until `now_ns`: closes the stream if that is a gap since the
    /// last byte (once; nothing without gap framing or with nothing received).
    pub fn idle(&mut self, now_ns: u64, out: &mut Vec<u8>) {
        if let (Some(gap), Some(last)) = (self.gap_ns, self.last_end_ns) {
            if !self.closed && now_ns.saturating_sub(last) >= gap {
                self.close(out);
            }
        }
    }

    /// The end of the capture: settles everything left, as bytes do.
    pub fn finish(&mut self, out: &mut Vec<u8>) {
        let mut lines = std::mem::take(&mut self.scratch);
        lines.clear();
        self.stream.finish(&mut lines);
        let decided = self.gap_ns.map(|_| Decided::Bytes);
        if let Some((held, t)) = self.held.take() {
            self.write(&held, t, decided, out);
        }
        for line in split(&lines) {
            let time = self.time_of(line);
            self.write(line, time, decided, out);
        }
        self.scratch = lines;
    }

    /// A gap: what the decoder holds is settled by it.
    fn close(&mut self, out: &mut Vec<u8>) {
        self.closed = true;
        let mut lines = std::mem::take(&mut self.scratch);
        lines.clear();
        self.stream.finish(&mut lines);
        if let Some((held, t)) = self.held.take() {
            // Nothing left to settle: the held frame ended where the gap began.
            let decided = if lines.is_empty() {
                Decided::Both
            } else {
                Decided::Bytes
            };
            self.write(&held, t, Some(decided), out);
        }
        for line in split(&lines) {
            let time = self.time_of(line);
            self.write(line, time, Some(Decided::Timing), out);
        }
        self.scratch = lines;
    }

    /// When the event on `line` started; forgets the chunks before it.
    fn time_of(&mut self, line: &[u8]) -> u64 {
        let Some((offset, _)) = offset_of(line) else {
            return self.last_end_ns.unwrap_or(0);
        };
        while self.chunks.len() > 1 && self.chunks[1].offset <= offset {
            self.chunks.pop_front();
        }
        match self.chunks.front() {
            Some(c) if offset >= c.offset => c
                .start_ns
                .saturating_add((offset - c.offset).saturating_mul(self.char_ns)),
            Some(c) => c.start_ns,
            None => self.last_end_ns.unwrap_or(0),
        }
    }

    /// Writes `line` with its time and what decided it, after its `"offset"`.
    fn write(&self, line: &[u8], time_ns: u64, decided: Option<Decided>, out: &mut Vec<u8>) {
        let Some((_, at)) = offset_of(line) else {
            out.extend_from_slice(line);
            out.push(b'\n');
            return;
        };
        out.extend_from_slice(&line[..at]);
        let (secs, nanos) = (time_ns / 1_000_000_000, time_ns % 1_000_000_000);
        out.extend_from_slice(format!(",\"time\":{secs}.{:06}", nanos / 1000).as_bytes());
        if let Some(d) = decided {
            out.extend_from_slice(format!(",\"decided_by\":\"{}\"", d.name()).as_bytes());
        }
        out.extend_from_slice(&line[at..]);
        out.push(b'\n');
    }
}

/// The lines in `text`, without their `\n`.
fn split(text: &[u8]) -> impl Iterator<Item = &[u8]> {
    text.split(|&b| b == b'\n').filter(|l| !l.is_empty())
}

/// An event line's offset, and where its value ends (`{"offset":N` is how every line starts).
fn offset_of(line: &[u8]) -> Option<(u64, usize)> {
    const HEAD: &[u8] = b"{\"offset\":";
    let rest = line.strip_prefix(HEAD)?;
    let digits = rest.iter().take_while(|b| b.is_ascii_digit()).count();
    let n = std::str::from_utf8(&rest[..digits]).ok()?.parse().ok()?;
    Some((n, HEAD.len() + digits))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stand-in stream: a frame is `AA` + one length byte + that many bytes, settled by the
    /// bytes only once a byte follows it (a longer frame could start there), or `BB` + one
    /// byte, settled as soon as it is complete (no other frame starts with `BB`); `finish`
    /// settles what is left, a byte of noise at a time where no frame fits.
    struct Toy {
        buf: Vec<u8>,
        at: u64,
    }

    impl Toy {
        fn emit(&mut self, n: usize, out: &mut Vec<u8>) {
            out.extend_from_slice(format!("{{\"offset\":{},\"len\":{n}}}\n", self.at).as_bytes());
            self.buf.drain(..n);
            self.at += n as u64;
        }
        fn frame_len(&self) -> Option<usize> {
            match self.buf.first() {
                Some(0xBB) => Some(2),
                Some(_) => (self.buf.len() >= 2).then(|| 2 + self.buf[1] as usize),
                None => None,
            }
        }
    }

    impl LineStream for Toy {
        fn push(&mut self, data: &[u8], out: &mut Vec<u8>) {
            self.buf.extend_from_slice(data);
            while let Some(n) = self.frame_len() {
                let settled = if self.buf[0] == 0xBB {
                    self.buf.len() >= n
                } else {
                    self.buf.len() > n
                };
                if !settled {
                    break;
                }
                self.emit(n, out);
            }
        }
        fn finish(&mut self, out: &mut Vec<u8>) {
            while !self.buf.is_empty() {
                let n = self.frame_len().unwrap_or(1).min(self.buf.len());
                self.emit(n, out);
            }
        }
    }

    fn toy() -> Box<dyn LineStream> {
        Box::new(Toy {
            buf: Vec::new(),
            at: 0,
        })
    }

    fn lines(out: &[u8]) -> Vec<String> {
        split(out)
            .map(|l| String::from_utf8(l.to_vec()).unwrap())
            .collect()
    }

    const MS: u64 = 1_000_000;

    #[test]
    fn gaps_close_frames_and_say_so() {
        // 1 ms a character, gaps of 3 ms.
        let mut t = Timed::new(toy(), MS, Some(3 * MS));
        let mut out = Vec::new();
        // Two frames back to back (the first settled by the bytes after it), then a gap.
        t.push(&[0xAA, 1, 0, 0xAA, 0, 0xAA], 1_000 * MS, &mut out);
        t.push(&[1, 7], 1_002 * MS, &mut out);
        // Quiet for 10 ms.
        t.idle(1_012 * MS, &mut out);
        // Idle again: nothing new.
        t.idle(1_020 * MS, &mut out);
        t.push(&[0xAA, 0], 1_030 * MS, &mut out);
        t.finish(&mut out);
        let got = lines(&out);
        assert_eq!(
            got,
            [
                r#"{"offset":0,"time":0.994000,"decided_by":"bytes","len":3}"#,
                r#"{"offset":3,"time":0.997000,"decided_by":"bytes","len":2}"#,
                r#"{"offset":5,"time":0.999000,"decided_by":"timing","len":3}"#,
                r#"{"offset":8,"time":1.028000,"decided_by":"bytes","len":2}"#,
            ]
        );
    }

    /// What decided each line, in order.
    fn decided(out: &[u8]) -> Vec<String> {
        lines(out)
            .iter()
            .map(|l| {
                let v: serde_json::Value = serde_json::from_str(l).unwrap();
                v["decided_by"].as_str().unwrap().to_owned()
            })
            .collect()
    }

    #[test]
    fn a_frame_the_bytes_settled_and_a_gap_followed_is_both() {
        let mut t = Timed::new(toy(), MS, Some(3 * MS));
        let mut out = Vec::new();
        // BB frames settle at once; the second is followed by a gap (idle), the first by bytes.
        t.push(&[0xBB, 1, 0xBB, 2], 10 * MS, &mut out);
        t.idle(20 * MS, &mut out);
        // A gap seen when the next chunk comes, after a BB frame and then noise (AA 05 …
        // waits for more): the frame is "bytes", what the gap settled "timing". The end of the
        // capture settles the last frame as bytes do.
        t.push(&[0xBB, 3, 0xAA, 5], 100 * MS, &mut out);
        t.push(&[0xBB, 4], 200 * MS, &mut out);
        t.finish(&mut out);
        assert_eq!(decided(&out), ["bytes", "both", "bytes", "timing", "bytes"]);
    }

    #[test]
    fn without_a_gap_lines_get_their_time_only() {
        let mut t = Timed::new(toy(), MS, None);
        let mut out = Vec::new();
        t.push(&[0xAA, 0, 0xAA], 5 * MS, &mut out);
        t.idle(500 * MS, &mut out);
        t.push(&[0], 600 * MS, &mut out);
        t.finish(&mut out);
        assert_eq!(
            lines(&out),
            [
                r#"{"offset":0,"time":0.002000,"len":2}"#,
                r#"{"offset":2,"time":0.004000,"len":2}"#,
            ]
        );
    }

    #[test]
    fn a_chunk_faster_than_the_line_starts_after_the_one_before() {
        // A pseudo-terminal delivers at once: 4 characters "started" 4 ms before they arrived,
        // which is before the previous chunk ended; times stay in order and no gap is seen.
        let mut t = Timed::new(toy(), MS, Some(3 * MS));
        let mut out = Vec::new();
        t.push(&[0xAA, 0], 100 * MS, &mut out);
        t.push(&[0xAA, 0, 0xAA, 0], 101 * MS, &mut out);
        t.finish(&mut out);
        let got = lines(&out);
        assert_eq!(got.len(), 3);
        assert!(got.iter().all(|l| l.contains("\"bytes\"")), "{got:?}");
        assert!(got[1].contains("\"time\":0.100000"), "{got:?}");
    }

    #[test]
    fn lines_without_an_offset_pass_unchanged() {
        assert_eq!(offset_of(b"{\"offset\":12,\"x\":1}"), Some((12, 12)));
        assert_eq!(offset_of(b"{\"message\":\"x\"}"), None);
        assert_eq!(offset_of(b"{\"offset\":x}"), None);
    }
}
