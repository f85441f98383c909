//! The baselines are fair only if they do the same work as the generated code: the hand-written
//! decoders and the deku peer must accept exactly the frames the generated decoders accept
//! (within the bench subset), decode them to the same values, reject the same corrupted
//! frames, and every contender must encode the stream back byte for byte.

use busspec_benches::mixed::{capture, Mixed, Proto};
use busspec_benches::peer;
use busspec_benches::{
    decode_all, encode_all, jobs, messages, stream_generated, stream_interp, Contender, Deku,
    Generated, Hand, Interp, Job, Message,
};
use busspec_protocols::sd::{self, Sd};
use busspec_protocols::ub2::{self, Ub2};
use busspec_protocols::{Decoded, Protocol};

fn assert_round_trip<C: Contender>(c: &C, mixed: &Mixed, who: &str) {
    let jobs = jobs(c, mixed);
    assert_eq!(
        decode_all(c, &mixed.bytes, &jobs),
        mixed.entries.len(),
        "{who} {}: every frame of the mixed stream decodes",
        mixed.proto.name()
    );
    let msgs = messages(c, mixed);
    let mut out = vec![0xA5u8; mixed.bytes.len() + 64];
    let n = encode_all(c, &msgs, &mut out)
        .unwrap_or_else(|| panic!("{who} {}: a message did not encode", mixed.proto.name()));
    assert_eq!(
        &out[..n],
        &mixed.bytes[..],
        "{who} {}: encoding the decoded stream gives it back",
        mixed.proto.name()
    );
}

#[test]
fn the_mixed_streams_hold_every_message_of_the_subset_in_both_directions() {
    for proto in Proto::ALL {
        let m = Mixed::new(proto);
        assert_eq!(m.entries.len(), busspec_benches::mixed::FRAMES);
        for name in proto.subset() {
            assert!(m.entries.iter().any(|e| e.message == *name), "{name}");
        }
        let requests = m
            .entries
            .iter()
            .filter(|e| e.direction == busspec_model::ir::Direction::Request)
            .count();
        assert!(requests > 20 && requests < 108, "{requests} requests");
    }
    let sd = Mixed::new(Proto::Sd);
    assert!(
        sd.entries.iter().any(|e| e.reply_to.is_some()),
        "the SD stream has replies only their request identifies"
    );
}

#[test]
fn every_contender_decodes_the_mixed_stream_and_encodes_it_back() {
    let ub2_spec = Proto::Ub2.spec();
    let sd_spec = Proto::Sd.spec();
    let ub2 = Mixed::from_spec(Proto::Ub2, &ub2_spec);
    let sd = Mixed::from_spec(Proto::Sd, &sd_spec);
    assert_round_trip(&Generated::<Ub2>::default(), &ub2, "generated");
    assert_round_trip(&Hand::<Ub2>::default(), &ub2, "hand-written");
    assert_round_trip(&Deku::<Ub2>::default(), &ub2, "deku");
    assert_round_trip(&Interp(&ub2_spec), &ub2, "interpreter");
    assert_round_trip(&Generated::<Sd>::default(), &sd, "generated");
    assert_round_trip(&Hand::<Sd>::default(), &sd, "hand-written");
    assert_round_trip(&Deku::<Sd>::default(), &sd, "deku");
    assert_round_trip(&Interp(&sd_spec), &sd, "interpreter");
}

fn mode_of(m: peer::ub2::Mode) -> ub2::ModeOfOperation {
    use peer::ub2::Mode;
    use ub2::ModeOfOperation;
    match m {
        Mode::EncoderDisabled => ModeOfOperation::EncoderDisabled,
        Mode::CloseLoopControl => ModeOfOperation::CloseLoopControl,
        Mode::OpenLoopControl => ModeOfOperation::OpenLoopControl,
        Mode::Unknown(v) => ModeOfOperation::Unknown(v),
    }
}

/// The deku peer's UB2 values in the generated crate's types.
fn deku_ub2_request(f: &peer::ub2::RequestFrame) -> Decoded<ub2::Request> {
    use peer::ub2::{Limit, Request as D};
    use ub2::{Capacitance, Request as G};
    let message = match f.message {
        D::ReferenceRun => G::ReferenceRun(ub2::request::ReferenceRun),
        D::GoToCapacitance { target } => G::GoToCapacitance(ub2::request::GoToCapacitance {
            target: Capacitance(target),
        }),
        D::GoToCapacitanceStatus => G::GoToCapacitanceStatus(ub2::request::GoToCapacitanceStatus),
        D::GoToFullStepPosition { target } => {
            G::GoToFullStepPosition(ub2::request::GoToFullStepPosition { target })
        }
        D::MoveFullSteps { steps } => G::MoveFullSteps(ub2::request::MoveFullSteps { steps }),
        D::SetModeOfOperation { mode } => G::SetModeOfOperation(ub2::request::SetModeOfOperation {
            mode: mode_of(mode),
        }),
        D::GetActualCapacitance => G::GetActualCapacitance(ub2::request::GetActualCapacitance),
        D::GetModeOfOperation => G::GetModeOfOperation(ub2::request::GetModeOfOperation),
        D::GetCCurveIndexedFullStepCapacitance { index } => G::GetCCurveIndexedFullStepCapacitance(
            ub2::request::GetCCurveIndexedFullStepCapacitance { index },
        ),
        D::GetControllerTemperature => {
            G::GetControllerTemperature(ub2::request::GetControllerTemperature)
        }
        D::GetFirmwareVersion => G::GetFirmwareVersion(ub2::request::GetFirmwareVersion),
        D::GetLimit {
            limit: Limit::LowerCustomer,
        } => G::GetLowerCustomerLimit(ub2::request::GetLowerCustomerLimit),
        D::GetLimit {
            limit: Limit::UpperCustomer,
        } => G::GetUpperCustomerLimit(ub2::request::GetUpperCustomerLimit),
    };
    Decoded {
        address: f.address,
        message,
    }
}

fn deku_ub2_response(f: &peer::ub2::ResponseFrame) -> Decoded<ub2::Response> {
    use peer::ub2::{Data, Echo, Limit, Response as D};
    use ub2::{Capacitance, Response as G};
    let message = match f.message {
        D::MovementStarted => G::MovementStarted(ub2::response::MovementStarted),
        D::MovementCompleted => G::MovementCompleted(ub2::response::MovementCompleted),
        D::MovementNotCompleted => G::MovementNotCompleted(ub2::response::MovementNotCompleted),
        D::NakLimitReached => G::NakLimitReached(ub2::response::NakLimitReached),
        D::NakIndexOutOfRange => G::NakIndexOutOfRange(ub2::response::NakIndexOutOfRange),
        D::Echo(Echo::SetModeOfOperationAck) => {
            G::SetModeOfOperationAck(ub2::response::SetModeOfOperationAck)
        }
        D::Data(d) => match d {
            Data::ActualCapacitance { capacitance } => {
                G::ActualCapacitance(ub2::response::ActualCapacitance {
                    capacitance: Capacitance(capacitance),
                })
            }
            Data::ActualModeOfOperation { mode } => {
                G::ActualModeOfOperation(ub2::response::ActualModeOfOperation {
                    mode: mode_of(mode),
                })
            }
            Data::CCurveEntry {
                index,
                full_steps,
                capacitance,
            } => G::CCurveEntry(ub2::response::CCurveEntry {
                index,
                full_steps,
                capacitance: Capacitance(capacitance),
            }),
            Data::ControllerTemperature { temperature } => {
                G::ControllerTemperature(ub2::response::ControllerTemperature { temperature })
            }
            Data::FirmwareVersion { firmware_version } => {
                G::FirmwareVersion(ub2::response::FirmwareVersion {
                    firmware_version: firmware_version.into(),
                })
            }
            Data::Limit {
                limit: Limit::LowerCustomer,
                capacitance,
            } => G::LowerCustomerLimit(ub2::response::LowerCustomerLimit {
                capacitance: Capacitance(capacitance),
            }),
            Data::Limit {
                limit: Limit::UpperCustomer,
                capacitance,
            } => G::UpperCustomerLimit(ub2::response::UpperCustomerLimit {
                capacitance: Capacitance(capacitance),
            }),
        },
    };
    Decoded {
        address: f.address,
        message,
    }
}

/// The deku peer's SD values in the generated crate's types.
fn deku_sd_request(f: &peer::sd::RequestFrame) -> Decoded<sd::Request> {
    use peer::sd::{Request as D, RuntimePart, StatusOp};
    use sd::{Angle, Request as G, Velocity};
    let message = match f.message {
        D::SetPoint {
            freshness,
            position,
        } => G::SetPoint(sd::request::SetPoint {
            freshness,
            position: Angle(position),
        }),
        D::ReadActualPosition { .. } => G::ReadActualPosition(sd::request::ReadActualPosition),
        D::SetVelocity { set_velocity } => G::SetVelocity(sd::request::SetVelocity {
            set_velocity: Velocity(set_velocity),
        }),
        D::ReadActualVelocity { .. } => G::ReadActualVelocity(sd::request::ReadActualVelocity),
        D::SetServoId { new_id, .. } => G::SetServoId(sd::request::SetServoId { new_id }),
        D::ReadTemperatures { .. } => G::ReadTemperatures(sd::request::ReadTemperatures),
        D::ReadHumidity { .. } => G::ReadHumidity(sd::request::ReadHumidity),
        D::ActuatorStatusWord {
            op: StatusOp::Read, ..
        } => G::ReadActuatorStatusWord(sd::request::ReadActuatorStatusWord),
        D::ActuatorStatusWord {
            op: StatusOp::Reset,
            ..
        } => G::ResetActuatorStatusWord(sd::request::ResetActuatorStatusWord),
        D::ReadTotalRuntime {
            part: RuntimePart::Hours,
            ..
        } => G::ReadTotalRuntimeHours(sd::request::ReadTotalRuntimeHours),
        D::ReadTotalRuntime {
            part: RuntimePart::MinSec,
            ..
        } => G::ReadTotalRuntimeMinSec(sd::request::ReadTotalRuntimeMinSec),
    };
    Decoded {
        address: f.address,
        message,
    }
}

fn deku_sd_response(r: &peer::sd::Reply) -> Decoded<sd::Response> {
    use peer::sd::{Reply, Response as D};
    use sd::{ActuatorStatusBits, Angle, Response as G, Temperature, Velocity};
    let (address, message) = match *r {
        Reply::TotalRuntimeHours { address, hours } => (
            address,
            G::TotalRuntimeHours(sd::response::TotalRuntimeHours {
                runtime_hours: hours,
            }),
        ),
        Reply::TotalRuntimeMinSec {
            address,
            minutes,
            seconds,
        } => (
            address,
            G::TotalRuntimeMinSec(sd::response::TotalRuntimeMinSec {
                runtime_minutes: minutes,
                runtime_seconds: seconds,
            }),
        ),
        Reply::Frame(f) => (
            f.address,
            match f.message {
                D::SetPointReply {
                    freshness,
                    position,
                } => G::SetPointReply(sd::response::SetPointReply {
                    freshness,
                    position: Angle(position),
                }),
                D::ActualPosition { position, .. } => {
                    G::ActualPosition(sd::response::ActualPosition {
                        position: Angle(position),
                    })
                }
                D::SetVelocityReply { actual_velocity } => {
                    G::SetVelocityReply(sd::response::SetVelocityReply {
                        actual_velocity: Velocity(actual_velocity),
                    })
                }
                D::ActualVelocity { actual_velocity } => {
                    G::ActualVelocity(sd::response::ActualVelocity {
                        actual_velocity: Velocity(actual_velocity),
                    })
                }
                D::SetServoIdReply { new_id, .. } => {
                    G::SetServoIdReply(sd::response::SetServoIdReply { new_id })
                }
                D::Temperatures {
                    motor_temperature,
                    pcb_temperature,
                } => G::Temperatures(sd::response::Temperatures {
                    motor_temperature: Temperature(motor_temperature),
                    pcb_temperature: Temperature(pcb_temperature),
                }),
                D::Humidity { humidity, .. } => G::Humidity(sd::response::Humidity { humidity }),
                D::ActuatorStatusWord {
                    status_bits,
                    status_arg2,
                } => G::ActuatorStatusWord(sd::response::ActuatorStatusWord {
                    status_bits: ActuatorStatusBits(status_bits),
                    status_arg2,
                }),
                D::TotalRuntime { .. } => panic!("0x22 is interpreted by its request"),
            },
        ),
    };
    Decoded { address, message }
}

/// The frames of the mixed stream, each also corrupted in one or two random bytes, with and
/// without the checksum repaired, and cut or extended by a byte: (direction is request,
/// frame, the request it answers).
fn variants(mixed: &Mixed, p: &busspec_model::Protocol) -> Vec<(bool, Vec<u8>, Option<Vec<u8>>)> {
    let mut rng = fastrand::Rng::with_seed(5);
    let c = &p.framing.checksum;
    let mut out = Vec::new();
    for e in &mixed.entries {
        let frame = mixed.frame(e).to_vec();
        let is_request = e.direction == busspec_model::ir::Direction::Request;
        out.push((is_request, frame.clone(), e.reply_to.clone()));
        for _ in 0..40 {
            let mut f = frame.clone();
            for _ in 0..rng.usize(1..=2) {
                let i = rng.usize(..f.len());
                f[i] = if rng.bool() { rng.u8(..) } else { rng.u8(..4) };
            }
            if rng.bool() {
                let n = c.len();
                let at = f.len() - n;
                let v = busspec_model::checksum::compute(&c.algorithm, &f[..at]);
                busspec_model::interp::write_uint(v, &mut f[at..], c.byte_order);
            }
            out.push((is_request, f, e.reply_to.clone()));
        }
        out.push((
            is_request,
            frame[..frame.len() - 1].to_vec(),
            e.reply_to.clone(),
        ));
        let mut longer = frame.clone();
        longer.push(0);
        out.push((is_request, longer, e.reply_to.clone()));
    }
    out
}

/// `other` must give what `generated` gives wherever the generated result lies in the subset,
/// and reject whatever the generated code rejects.
fn agree<T: PartialEq + std::fmt::Debug, E: std::fmt::Debug>(
    generated: Result<T, busspec_protocols::DecodeError>,
    other: Result<T, E>,
    in_subset: impl Fn(&T) -> bool,
    what: &str,
) -> bool {
    match (generated, other) {
        (Ok(g), Ok(o)) => {
            assert_eq!(g, o, "{what}");
            true
        }
        (Ok(g), Err(_)) => {
            assert!(!in_subset(&g), "{what}: rejected, but it decodes to {g:?}");
            false
        }
        (Err(g), Ok(o)) => panic!("{what}: the generated code says {g}, this decodes {o:?}"),
        (Err(_), Err(_)) => false,
    }
}

#[test]
fn the_hand_written_decoders_and_the_deku_peer_accept_and_reject_what_the_generated_code_does() {
    let hex = busspec_model::interp::format_hex;
    for proto in Proto::ALL {
        let p = proto.spec();
        let mixed = Mixed::from_spec(proto, &p);
        let subset = proto.subset();
        let mut accepted = 0;
        let mut rejected = 0;
        for (is_request, f, reply_to) in variants(&mixed, &p) {
            let what = format!("{} {}", proto.name(), hex(&f));
            let outcomes = match (proto, is_request) {
                (Proto::Ub2, true) => {
                    let inn = |d: &Decoded<ub2::Request>| subset.contains(&d.message.name());
                    let g = ub2::Request::decode(&f);
                    let h = busspec_benches::hand::ub2::decode_request(&f);
                    let d = busspec_benches::peer::ub2::decode_request(&f)
                        .map(|d| deku_ub2_request(&d));
                    [agree(g, h, inn, &what), agree(g, d, inn, &what)]
                }
                (Proto::Ub2, false) => {
                    let inn = |d: &Decoded<ub2::Response>| subset.contains(&d.message.name());
                    let g = ub2::Response::decode(&f);
                    let h = busspec_benches::hand::ub2::decode_response(&f, None);
                    let d = busspec_benches::peer::ub2::decode_response(&f, None)
                        .map(|d| deku_ub2_response(&d));
                    [agree(g, h, inn, &what), agree(g, d, inn, &what)]
                }
                (Proto::Sd, true) => {
                    let inn = |d: &Decoded<sd::Request>| subset.contains(&d.message.name());
                    let g = sd::Request::decode(&f);
                    let h = busspec_benches::hand::sd::decode_request(&f);
                    let d =
                        busspec_benches::peer::sd::decode_request(&f).map(|d| deku_sd_request(&d));
                    [agree(g, h, inn, &what), agree(g, d, inn, &what)]
                }
                (Proto::Sd, false) => {
                    let inn = |d: &Decoded<sd::Response>| subset.contains(&d.message.name());
                    let q = reply_to
                        .as_deref()
                        .map(|r| sd::Request::decode(r).unwrap().message);
                    let g = match &q {
                        Some(q) => sd::Response::decode_reply(&f, q),
                        None => sd::Response::decode(&f),
                    };
                    let h = busspec_benches::hand::sd::decode_response(&f, q.as_ref());
                    // A reply refused as not this request's is refused with its code.
                    if let (Err(e), Err(busspec_protocols::DecodeError::NotAReply { .. })) = (g, h)
                    {
                        assert_eq!(h, Err(e), "{what}: not a reply");
                    }
                    let dq = reply_to
                        .as_deref()
                        .map(|r| peer::sd::decode_request(r).unwrap());
                    let d =
                        peer::sd::decode_response(&f, dq.as_ref()).map(|d| deku_sd_response(&d));
                    [agree(g, h, inn, &what), agree(g, d, inn, &what)]
                }
                // Proto::ALL: the protocols with hand-written and deku baselines.
                (Proto::Modbus | Proto::Dynamixel, _) => unreachable!("no baselines"),
            };
            assert_eq!(
                outcomes[0], outcomes[1],
                "{what}: hand-written and deku differ"
            );
            if outcomes[0] {
                accepted += 1;
            } else {
                rejected += 1;
            }
        }
        // Both outcomes happen often, so neither side of the comparison is vacuous.
        assert!(
            accepted > 500 && rejected > 2000,
            "{accepted} accepted, {rejected} rejected"
        );
    }
}

/// A UB2 reply decodes only after a request that may get it, in every contender: each response
/// of the mixed stream (and its corrupted variants) after each request of the subset.
#[test]
fn the_ub2_baselines_refuse_a_reply_the_request_may_not_get_as_the_generated_code_does() {
    let hex = busspec_model::interp::format_hex;
    let p = Proto::Ub2.spec();
    let mixed = Mixed::from_spec(Proto::Ub2, &p);
    let subset = Proto::Ub2.subset();
    let mut requests: Vec<&[u8]> = Vec::new();
    let mut names = Vec::new();
    for e in &mixed.entries {
        if e.direction == busspec_model::ir::Direction::Request && !names.contains(&e.message) {
            names.push(e.message.clone());
            requests.push(mixed.frame(e));
        }
    }
    assert_eq!(requests.len(), 13, "every request of the subset");
    let (mut accepted, mut not_a_reply) = (0, 0);
    for (is_request, f, _) in variants(&mixed, &p) {
        if is_request {
            continue;
        }
        for r in &requests {
            let what = format!("ub2 {} after {}", hex(&f), hex(r));
            let q = ub2::Request::decode(r).unwrap();
            let dq = peer::ub2::decode_request(r).unwrap();
            let inn = |d: &Decoded<ub2::Response>| subset.contains(&d.message.name());
            let g = ub2::Response::decode_reply(&f, &q.message);
            let h = busspec_benches::hand::ub2::decode_response(&f, Some(&q.message));
            let d = peer::ub2::decode_response(&f, Some(&dq)).map(|d| deku_ub2_response(&d));
            // A frame that decodes on its own but is refused as this request's reply: refused
            // by each baseline as not a reply, with the code.
            if let (Err(e @ busspec_protocols::DecodeError::NotAReply { .. }), Ok(alone)) =
                (g, ub2::Response::decode(&f))
            {
                if inn(&alone) {
                    assert_eq!(h, Err(e), "{what}: hand-written");
                    assert!(
                        matches!(d, Err(peer::Error::NotAReply)),
                        "{what}: deku gives {d:?}"
                    );
                    not_a_reply += 1;
                }
            }
            let outcomes = [agree(g, h, inn, &what), agree(g, d, inn, &what)];
            assert_eq!(
                outcomes[0], outcomes[1],
                "{what}: hand-written and deku differ"
            );
            accepted += usize::from(outcomes[0]);
        }
    }
    // Both outcomes happen often, so neither side of the comparison is vacuous.
    assert!(
        accepted > 200 && not_a_reply > 2000,
        "{accepted} accepted, {not_a_reply} not a reply"
    );
}

/// The synthetic capture of `P` is 1 % noise, and `P`'s generated stream decoder finds in it
/// what the interpreter's does.
fn capture_agrees<P: Protocol>() {
    let proto = Proto::of::<P>();
    let p = proto.spec();
    let cap = capture(&p, 64 << 10);
    assert_eq!(cap.len(), 64 << 10);
    let generated = stream_generated::<P>(&cap);
    let interp = stream_interp(&p, &cap);
    assert_eq!(generated, interp, "{}", proto.name());
    assert_eq!(generated.bytes, cap.len() as u64);
    // 1 % noise, and at most one cut frame at the end.
    let share = generated.skipped_bytes as f64 / cap.len() as f64;
    assert!((0.007..0.013).contains(&share), "{}: {share}", proto.name());
    assert!(generated.frames > 5000, "{}: {generated:?}", proto.name());
}

#[test]
fn the_capture_is_one_percent_noise_and_the_stream_decoders_agree_on_it() {
    capture_agrees::<Ub2>();
    capture_agrees::<Sd>();
}

#[test]
fn jobs_carry_the_request_only_for_replies_that_need_it() {
    let mixed = Mixed::new(Proto::Sd);
    let jobs = jobs(&Generated::<Sd>::default(), &mixed);
    for (job, e) in jobs.iter().zip(&mixed.entries) {
        match job {
            Job::Request(_) => assert!(e.reply_to.is_none()),
            Job::Response(_, q) => assert_eq!(q.is_some(), e.reply_to.is_some()),
        }
    }
}

/// Encodes `g` with the generated code, `h` (the same message) by hand and `d` (the deku
/// peer's) with deku: all three refuse it or all write the same bytes. Returns whether they
/// wrote it.
fn encodes_alike<G, H, D>(
    (gc, hc, dc): (&G, &H, &D),
    g: &Message<G::Request, G::Response>,
    d: &Message<D::Request, D::Response>,
    what: &str,
) -> bool
where
    G: Contender,
    H: Contender<Request = G::Request, Response = G::Response>,
    D: Contender,
{
    fn enc<C: Contender>(c: &C, m: &Message<C::Request, C::Response>) -> Option<Vec<u8>> {
        let mut buf = [0u8; 64];
        let n = match m {
            Message::Request(q) => c.encode_request(q, &mut buf),
            Message::Response(r) => c.encode_response(r, &mut buf),
        };
        n.ok().map(|n| buf[..n].to_vec())
    }
    let generated = enc(gc, g);
    assert_eq!(generated, enc(hc, g), "{what}: hand-written");
    assert_eq!(generated, enc(dc, d), "{what}: deku");
    generated.is_some()
}

fn sd_reply_address(r: &mut peer::sd::Reply) -> &mut u8 {
    use peer::sd::Reply;
    match r {
        Reply::Frame(f) => &mut f.address,
        Reply::TotalRuntimeHours { address, .. } | Reply::TotalRuntimeMinSec { address, .. } => {
            address
        }
    }
}

#[test]
fn the_hand_written_and_deku_encoders_refuse_what_the_generated_encoders_refuse() {
    // Every message of both mixed streams to every address, and the ranged fields of the
    // subset to values in and out of their ranges.
    let (mut written, mut refused) = (0, 0);
    let mut count = |ok: bool| if ok { written += 1 } else { refused += 1 };

    let contenders = (
        &Generated::<Ub2>::default(),
        &Hand::<Ub2>::default(),
        &Deku::<Ub2>::default(),
    );
    let mixed = Mixed::new(Proto::Ub2);
    let gs = messages(contenders.0, &mixed);
    let ds = messages(contenders.2, &mixed);
    for (g, d) in gs.iter().zip(&ds) {
        for a in 0..=255u8 {
            let (mut g, mut d) = (g.clone(), d.clone());
            match (&mut g, &mut d) {
                (Message::Request(g), Message::Request(d)) => (g.address, d.address) = (a, a),
                (Message::Response(g), Message::Response(d)) => (g.address, d.address) = (a, a),
                _ => unreachable!(),
            }
            count(encodes_alike(
                contenders,
                &g,
                &d,
                &format!("ub2 {g:?} to {a:#04x}"),
            ));
        }
        for v in [0u16, 1, 498, 499, 500, 501, 0x8000, 0xFFFF] {
            let (mut g, mut d) = (g.clone(), d.clone());
            match (&mut g, &mut d) {
                (
                    Message::Request(Decoded {
                        message:
                            ub2::Request::GetCCurveIndexedFullStepCapacitance(
                                ub2::request::GetCCurveIndexedFullStepCapacitance { index },
                            ),
                        ..
                    }),
                    Message::Request(peer::ub2::RequestFrame {
                        message:
                            peer::ub2::Request::GetCCurveIndexedFullStepCapacitance { index: i },
                        ..
                    }),
                )
                | (
                    Message::Response(Decoded {
                        message:
                            ub2::Response::CCurveEntry(ub2::response::CCurveEntry { index, .. }),
                        ..
                    }),
                    Message::Response(peer::ub2::ResponseFrame {
                        message:
                            peer::ub2::Response::Data(peer::ub2::Data::CCurveEntry { index: i, .. }),
                        ..
                    }),
                ) => (*index, *i) = (v, v),
                _ => break,
            }
            count(encodes_alike(contenders, &g, &d, &format!("ub2 {g:?}")));
        }
    }

    let contenders = (
        &Generated::<Sd>::default(),
        &Hand::<Sd>::default(),
        &Deku::<Sd>::default(),
    );
    let mixed = Mixed::new(Proto::Sd);
    let gs = messages(contenders.0, &mixed);
    let ds = messages(contenders.2, &mixed);
    for (g, d) in gs.iter().zip(&ds) {
        for a in 0..=255u8 {
            let (mut g, mut d) = (g.clone(), d.clone());
            match (&mut g, &mut d) {
                (Message::Request(g), Message::Request(d)) => (g.address, d.address) = (a, a),
                (Message::Response(g), Message::Response(d)) => {
                    (g.address, *sd_reply_address(d)) = (a, a)
                }
                _ => unreachable!(),
            }
            count(encodes_alike(
                contenders,
                &g,
                &d,
                &format!("sd {g:?} to {a:#04x}"),
            ));
        }
        for v in 0..=255u8 {
            use peer::sd::{Reply, Request as DQ, RequestFrame, Response as DR, ResponseFrame};
            let (mut g, mut d) = (g.clone(), d.clone());
            match (&mut g, &mut d) {
                (
                    Message::Request(Decoded {
                        message: sd::Request::SetServoId(sd::request::SetServoId { new_id }),
                        ..
                    }),
                    Message::Request(RequestFrame {
                        message:
                            DQ::SetServoId {
                                new_id: i,
                                new_id_repeat: r,
                            },
                        ..
                    }),
                )
                | (
                    Message::Response(Decoded {
                        message:
                            sd::Response::SetServoIdReply(sd::response::SetServoIdReply { new_id }),
                        ..
                    }),
                    Message::Response(Reply::Frame(ResponseFrame {
                        message:
                            DR::SetServoIdReply {
                                new_id: i,
                                new_id_repeat: r,
                            },
                        ..
                    })),
                )
                | (
                    Message::Response(Decoded {
                        message: sd::Response::Humidity(sd::response::Humidity { humidity: new_id }),
                        ..
                    }),
                    Message::Response(Reply::Frame(ResponseFrame {
                        message:
                            DR::Humidity {
                                humidity: i,
                                humidity_repeat: r,
                            },
                        ..
                    })),
                ) => (*new_id, *i, *r) = (v, v, v),
                (
                    Message::Response(Decoded {
                        message:
                            sd::Response::TotalRuntimeMinSec(sd::response::TotalRuntimeMinSec {
                                runtime_minutes,
                                runtime_seconds,
                            }),
                        ..
                    }),
                    Message::Response(Reply::TotalRuntimeMinSec {
                        minutes, seconds, ..
                    }),
                ) => {
                    // Minutes and seconds out of range in turn.
                    let (m, s) = if v % 2 == 0 { (v, 7) } else { (7, v) };
                    (*runtime_minutes, *minutes) = (m, m);
                    (*runtime_seconds, *seconds) = (s, s);
                }
                _ => break,
            }
            count(encodes_alike(contenders, &g, &d, &format!("sd {g:?}")));
        }
    }
    // Both outcomes happen often, so neither side of the comparison is vacuous.
    assert!(
        written > 3000 && refused > 20000,
        "{written} written, {refused} refused"
    );
}
