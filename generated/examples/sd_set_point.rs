//! Encode an SD set point, decode the actuator's reply as the answer to it, and split a noisy
//! capture into frames. `cargo run -p busspec-protocols --example sd_set_point`

use busspec_protocols::sd::{
    request, response, Angle, Event, Request, Response, StreamDecoder, MAX_FRAME_LEN,
};
use busspec_protocols::DecodeError;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Move actuator 5 to +45°, freshness counter 3.
    let set_point = Request::SetPoint(request::SetPoint {
        freshness: 3,
        position: Angle::from_value(45.0).ok_or("45° is not a whole number of counts")?,
    });
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = set_point.encode(0x05, &mut buf)?;
    println!("request  {:02X?}", &buf[..n]);

    // The actuator's reply (here encoded as a simulator would; on a bus, read from the port),
    // decoded as the answer to our request.
    let mut rx = [0u8; MAX_FRAME_LEN];
    let reply = Response::SetPointReply(response::SetPointReply {
        freshness: 12,
        position: Angle::from_raw(509),
    });
    let m = reply.encode(0x05, &mut rx)?;
    let got = Response::decode_reply(&rx[..m], &set_point)?;
    assert!(got.message.answers(&set_point));
    println!("reply    {:02X?} = {:?}", &rx[..m], got.message);

    // One corrupted byte: the error says what and where.
    rx[3] ^= 0x01;
    match Response::decode(&rx[..m]) {
        Err(e @ DecodeError::ChecksumMismatch { .. }) => println!("corrupted: {e}"),
        other => return Err(format!("a corrupted frame decoded: {other:?}").into()),
    }

    // A capture: noise, the request, more noise; in chunks of any size.
    let mut capture = vec![0x00, 0xFF, 0x13];
    capture.extend_from_slice(&buf[..n]);
    capture.push(0x55);
    let mut stream = StreamDecoder::new(None);
    let mut events: Vec<Event> = Vec::new();
    for chunk in capture.chunks(4) {
        events.extend(stream.feed(chunk));
    }
    while let Some(e) = stream.finish() {
        events.push(e);
    }
    for e in &events {
        println!("{e:?}");
    }
    let decoded = Request::decode(&buf[..n])?;
    assert_eq!(decoded.message, set_point);
    assert_eq!(decoded.address, 0x05);
    if let Request::SetPoint(request::SetPoint { position, .. }) = decoded.message {
        println!("set point {} {}", position.value(), Angle::SYMBOL);
    }
    Ok(())
}
