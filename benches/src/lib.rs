//! What busspec's benches measure, shared by the criterion benches (`benches/`), the
//! instruction counter (`src/bin/icount.rs`) and the tests that hold every contender to the
//! generated code (`tests/`).
//!
//! Contenders, each behind [`Contender`]:
//! - [`Generated`]: the generated codec crate (`busspec-protocols`), the thing measured;
//! - [`Hand`]: decoders and encoders written by hand ([`hand`]), the practical limit;
//! - [`Deku`]: the same frames derived with deku ([`peer`]), what people would otherwise use;
//! - [`Interp`]: busspec's run-time interpreter, the oracle.
//!
//! Every contender decodes the same [`mixed::Mixed`] stream (the spec's example frames of a
//! subset of messages every contender implements, [`mixed::Proto::subset`]).

pub mod hand;
pub mod mixed;
pub mod peer;

use std::hint::black_box;
use std::ops::Range;

use busspec_model::interp;
use busspec_model::ir::{Direction, Protocol};
use busspec_protocols::sd::{self, Sd};
use busspec_protocols::ub2::{self, Ub2};
use busspec_protocols::{Decoded, Message as _, ResponseMessage};
use mixed::Mixed;

/// One decoder/encoder of one protocol.
pub trait Contender {
    /// A decoded request, with its address.
    type Request: Clone;
    /// A decoded response, with its address.
    type Response: Clone;
    type DecodeError: std::fmt::Debug;
    type EncodeError: std::fmt::Debug;
    fn decode_request(&self, frame: &[u8]) -> Result<Self::Request, Self::DecodeError>;
    /// `request` is given for responses only their request identifies.
    fn decode_response(
        &self,
        frame: &[u8],
        request: Option<&Self::Request>,
    ) -> Result<Self::Response, Self::DecodeError>;
    fn encode_request(&self, m: &Self::Request, buf: &mut [u8])
        -> Result<usize, Self::EncodeError>;
    fn encode_response(
        &self,
        m: &Self::Response,
        buf: &mut [u8],
    ) -> Result<usize, Self::EncodeError>;
}

/// The generated codec of protocol `P` (`busspec_protocols::ub2::Ub2`, ...), through the
/// [`busspec_protocols::Protocol`] and [`busspec_protocols::Message`] traits.
#[derive(Debug, Clone, Copy, Default)]
pub struct Generated<P>(std::marker::PhantomData<P>);

/// The hand-written decoders and encoders of [`hand`], for protocol `P`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Hand<P>(std::marker::PhantomData<P>);

/// The deku-derived peer of [`peer`], for protocol `P`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Deku<P>(std::marker::PhantomData<P>);

impl<P: busspec_protocols::Protocol> Contender for Generated<P> {
    type Request = Decoded<P::Request>;
    type Response = Decoded<P::Response>;
    type DecodeError = busspec_protocols::DecodeError;
    type EncodeError = busspec_protocols::EncodeError;
    #[inline]
    fn decode_request(&self, frame: &[u8]) -> Result<Self::Request, Self::DecodeError> {
        P::decode_request(frame)
    }
    #[inline]
    fn decode_response(
        &self,
        frame: &[u8],
        request: Option<&Self::Request>,
    ) -> Result<Self::Response, Self::DecodeError> {
        P::Response::decode_as_reply(frame, request.map(|r| &r.message))
    }
    #[inline]
    fn encode_request(
        &self,
        m: &Self::Request,
        buf: &mut [u8],
    ) -> Result<usize, Self::EncodeError> {
        m.message.encode(m.address, buf)
    }
    #[inline]
    fn encode_response(
        &self,
        m: &Self::Response,
        buf: &mut [u8],
    ) -> Result<usize, Self::EncodeError> {
        m.message.encode(m.address, buf)
    }
}

/// The hand-written contender of one protocol: its module in [`hand`] and its generated crate
/// module (the typed values it produces).
macro_rules! hand_contender {
    ($p:ty, $m:ident) => {
        impl Contender for Hand<$p> {
            type Request = Decoded<$m::Request>;
            type Response = Decoded<$m::Response>;
            type DecodeError = busspec_protocols::DecodeError;
            type EncodeError = hand::EncodeError;
            #[inline]
            fn decode_request(&self, frame: &[u8]) -> Result<Self::Request, Self::DecodeError> {
                hand::$m::decode_request(frame)
            }
            #[inline]
            fn decode_response(
                &self,
                frame: &[u8],
                request: Option<&Self::Request>,
            ) -> Result<Self::Response, Self::DecodeError> {
                hand::$m::decode_response(frame, request.map(|r| &r.message))
            }
            #[inline]
            fn encode_request(
                &self,
                m: &Self::Request,
                buf: &mut [u8],
            ) -> Result<usize, Self::EncodeError> {
                hand::subset(
                    m.message.name(),
                    hand::$m::encode_request(&m.message, m.address, buf),
                )
            }
            #[inline]
            fn encode_response(
                &self,
                m: &Self::Response,
                buf: &mut [u8],
            ) -> Result<usize, Self::EncodeError> {
                hand::subset(
                    m.message.name(),
                    hand::$m::encode_response(&m.message, m.address, buf),
                )
            }
        }
    };
}

hand_contender!(Ub2, ub2);
hand_contender!(Sd, sd);

/// The deku-derived contender of one protocol: its module in [`peer`] and its response type.
macro_rules! deku_contender {
    ($p:ty, $m:ident, $response:ident) => {
        impl Contender for Deku<$p> {
            type Request = peer::$m::RequestFrame;
            type Response = peer::$m::$response;
            type DecodeError = peer::Error;
            type EncodeError = peer::Error;
            #[inline]
            fn decode_request(&self, frame: &[u8]) -> Result<Self::Request, peer::Error> {
                peer::$m::decode_request(frame)
            }
            #[inline]
            fn decode_response(
                &self,
                frame: &[u8],
                request: Option<&Self::Request>,
            ) -> Result<Self::Response, peer::Error> {
                peer::$m::decode_response(frame, request)
            }
            #[inline]
            fn encode_request(
                &self,
                m: &Self::Request,
                buf: &mut [u8],
            ) -> Result<usize, peer::Error> {
                peer::$m::encode_request(m, buf)
            }
            #[inline]
            fn encode_response(
                &self,
                m: &Self::Response,
                buf: &mut [u8],
            ) -> Result<usize, peer::Error> {
                peer::$m::encode_response(m, buf)
            }
        }
    };
}

deku_contender!(Ub2, ub2, ResponseFrame);
deku_contender!(Sd, sd, Reply);

/// busspec's interpreter over a loaded spec.
pub struct Interp<'p>(pub &'p Protocol);

/// Why the interpreter did not encode a frame into the caller's buffer.
#[derive(Debug)]
pub enum InterpEncodeError {
    Encode(interp::EncodeError),
    BufferTooSmall { needed: usize },
}

impl<'p> Contender for Interp<'p> {
    type Request = interp::Frame<'p>;
    type Response = interp::Frame<'p>;
    type DecodeError = interp::DecodeError;
    type EncodeError = InterpEncodeError;
    fn decode_request(&self, frame: &[u8]) -> Result<interp::Frame<'p>, interp::DecodeError> {
        interp::decode(self.0, Some(Direction::Request), None, frame)
    }
    fn decode_response(
        &self,
        frame: &[u8],
        request: Option<&interp::Frame<'p>>,
    ) -> Result<interp::Frame<'p>, interp::DecodeError> {
        let reply_to = request.map(|r| r.message.index);
        interp::decode(self.0, Some(Direction::Response), reply_to, frame)
    }
    fn encode_request(
        &self,
        m: &interp::Frame,
        buf: &mut [u8],
    ) -> Result<usize, InterpEncodeError> {
        self.encode_response(m, buf)
    }
    fn encode_response(
        &self,
        m: &interp::Frame,
        buf: &mut [u8],
    ) -> Result<usize, InterpEncodeError> {
        let wire = interp::encode(self.0, m.message, m.address, &m.values)
            .map_err(InterpEncodeError::Encode)?;
        buf.get_mut(..wire.len())
            .ok_or(InterpEncodeError::BufferTooSmall { needed: wire.len() })?
            .copy_from_slice(&wire);
        Ok(wire.len())
    }
}

/// One frame of the mixed stream as a contender is handed it: where it lies, and for a reply
/// only its request identifies, that request already decoded by the same contender.
#[derive(Debug, Clone)]
pub enum Job<Q> {
    Request(Range<usize>),
    Response(Range<usize>, Option<Q>),
}

/// The mixed stream's jobs for contender `c` (decodes the requests replies need; not timed).
pub fn jobs<C: Contender>(c: &C, mixed: &Mixed) -> Vec<Job<C::Request>> {
    mixed
        .entries
        .iter()
        .map(|e| match e.direction {
            Direction::Request => Job::Request(e.range.clone()),
            Direction::Response => Job::Response(
                e.range.clone(),
                e.reply_to.as_ref().map(|r| {
                    c.decode_request(r)
                        .unwrap_or_else(|err| panic!("request of {}: {err:?}", e.message))
                }),
            ),
        })
        .collect()
}

/// Decodes every frame of the stream in order; returns how many decoded. Each result goes
/// through `black_box` by reference, so none is optimised away and none is copied (passed by
/// value, the 56-byte result was copied to another stack slot: 8 instructions a frame of
/// `benches/icount.sh` that no caller of a decoder pays).
#[inline(never)]
pub fn decode_all<C: Contender>(c: &C, bytes: &[u8], jobs: &[Job<C::Request>]) -> usize {
    let mut ok = 0;
    for job in jobs {
        let decoded = match job {
            Job::Request(r) => black_box(&c.decode_request(&bytes[r.clone()])).is_ok(),
            Job::Response(r, q) => {
                black_box(&c.decode_response(&bytes[r.clone()], q.as_ref())).is_ok()
            }
        };
        ok += usize::from(decoded);
    }
    ok
}

/// [`decode_all`] through a generated module's borrowed views (`RequestView`/`ResponseView`):
/// each view made (every check the owned decode makes, the lists lent in place) and passed to
/// `black_box` by reference, as `decode_all` passes the owned result.
macro_rules! decode_all_views {
    ($name:ident, $m:ident) => {
        #[doc = concat!("[`decode_all`] of `", stringify!($m), "` through its views.")]
        #[inline(never)]
        pub fn $name(bytes: &[u8], jobs: &[Job<Decoded<busspec_protocols::$m::Request>>]) -> usize {
            use busspec_protocols::$m::{RequestView, ResponseView};
            let mut ok = 0;
            for job in jobs {
                let decoded = match job {
                    Job::Request(r) => black_box(&RequestView::decode(&bytes[r.clone()])).is_ok(),
                    Job::Response(r, q) => {
                        let frame = &bytes[r.clone()];
                        match q {
                            Some(q) => {
                                black_box(&ResponseView::decode_reply(frame, &q.message)).is_ok()
                            }
                            None => black_box(&ResponseView::decode(frame)).is_ok(),
                        }
                    }
                };
                ok += usize::from(decoded);
            }
            ok
        }
    };
}

decode_all_views!(decode_all_modbus_views, modbus);
decode_all_views!(decode_all_dynamixel_views, dynamixel);

/// A decoded message, for the encode benches.
#[derive(Debug, Clone)]
pub enum Message<Q, R> {
    Request(Q),
    Response(R),
}

/// Every frame of the stream decoded by `c` (not timed); panics on a frame it rejects.
pub fn messages<C: Contender>(c: &C, mixed: &Mixed) -> Vec<Message<C::Request, C::Response>> {
    let jobs = jobs(c, mixed);
    jobs.iter()
        .zip(&mixed.entries)
        .map(|(job, e)| match job {
            Job::Request(r) => Message::Request(
                c.decode_request(&mixed.bytes[r.clone()])
                    .unwrap_or_else(|err| panic!("{}: {err:?}", e.message)),
            ),
            Job::Response(r, q) => Message::Response(
                c.decode_response(&mixed.bytes[r.clone()], q.as_ref())
                    .unwrap_or_else(|err| panic!("{}: {err:?}", e.message)),
            ),
        })
        .collect()
}

/// Encodes every message back to back into `out`; returns the bytes written, or `None` if
/// one did not encode.
#[inline(never)]
pub fn encode_all<C: Contender>(
    c: &C,
    messages: &[Message<C::Request, C::Response>],
    out: &mut [u8],
) -> Option<usize> {
    let mut at = 0;
    for m in messages {
        let buf = out.get_mut(at..)?;
        let n = match m {
            Message::Request(q) => c.encode_request(q, buf),
            Message::Response(r) => c.encode_response(r, buf),
        };
        at += n.ok()?;
    }
    Some(at)
}

/// What a stream decoder found in a capture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamCount {
    pub frames: u64,
    pub ambiguous: u64,
    pub skipped_bytes: u64,
    /// Frames that checksum but break a rule of the spec.
    pub out_of_spec: u64,
    /// Bytes accounted for by all events.
    pub bytes: u64,
}

/// The generated streaming decoder of protocol `P` over a whole capture, sniffing both
/// directions.
#[inline(never)]
pub fn stream_generated<P: busspec_protocols::Protocol>(capture: &[u8]) -> StreamCount {
    use busspec_protocols::stream::{Event, StreamDecoder};
    let mut d = StreamDecoder::<P>::new(None);
    let mut n = StreamCount::default();
    let mut count = |ev: Event<P::Request, P::Response>| {
        n.bytes += ev.len();
        match ev {
            Event::Request { .. } | Event::Response { .. } => n.frames += 1,
            Event::Ambiguous { .. } => n.ambiguous += 1,
            Event::OutOfSpec { .. } => n.out_of_spec += 1,
            Event::Skipped { len, .. } => n.skipped_bytes += len,
        }
    };
    d.feed(capture).for_each(|ev| count(black_box(ev)));
    while let Some(ev) = d.finish() {
        count(black_box(ev));
    }
    n
}

/// The interpreter's streaming decoder over a whole capture, sniffing both directions.
pub fn stream_interp(p: &Protocol, capture: &[u8]) -> StreamCount {
    use busspec_model::stream::{Event, StreamDecoder};
    let mut d = StreamDecoder::new(p, None);
    let mut n = StreamCount::default();
    let mut events = d.push(capture);
    events.extend(d.flush());
    for ev in events {
        n.bytes += ev.bytes().len() as u64;
        match ev {
            Event::Frame { .. } => n.frames += 1,
            Event::Ambiguous { .. } => n.ambiguous += 1,
            Event::OutOfSpec { .. } => n.out_of_spec += 1,
            Event::Skipped { bytes, .. } => n.skipped_bytes += bytes.len() as u64,
        }
    }
    n
}

/// The memory floor: one pass over the bytes adding them up, as the compiler makes of it
/// (auto-vectorised on x86-64).
#[inline(never)]
pub fn plain_sum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b))
}
