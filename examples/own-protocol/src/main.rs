//! Ask thermostat 1 for its temperature and decode its answer (here a frame from the spec's
//! examples, §4.1; on a bus, the bytes read from the port). `cargo run` in this directory.

use busspec_runtime::{DecodeError, Protocol};
use own_protocol::thermo::{DeciCelsius, Mode, Request, Response, Thermo, MAX_FRAME_LEN};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let request = Request::ReadTemperature(own_protocol::thermo::request::ReadTemperature);
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = request.encode(0x01, &mut buf)?;
    println!("request  {:02X?} {request:?}", &buf[..n]);

    // The reply §4.1 prints: 21.5 °C measured, set point 22.0 °C, 45 % humidity.
    let rx = [0xA5, 0x01, 0x90, 0x00, 0xD7, 0x00, 0xDC, 0x5A, 0x66, 0x93];
    let reply = Response::decode_reply(&rx, &request)?;
    println!("reply    {:02X?} {:?}", rx, reply.message);
    if let Response::Temperature(own_protocol::thermo::response::Temperature {
        measured,
        setpoint,
        humidity,
    }) = reply.message
    {
        println!(
            "thermostat {}: {} {}, set point {} {}, humidity {} {}",
            reply.address,
            measured.value(),
            DeciCelsius::SYMBOL,
            setpoint.value(),
            DeciCelsius::SYMBOL,
            humidity.value(),
            own_protocol::thermo::Humidity::SYMBOL,
        );
    }

    // Every thermostat on the bus to heating: a broadcast, which nobody answers.
    let heat = Request::SetMode(own_protocol::thermo::request::SetMode { mode: Mode::Heat });
    let broadcast = Thermo::BUS
        .broadcast_address
        .ok_or("no broadcast address")?;
    let n = heat.encode(broadcast, &mut buf)?;
    println!(
        "request  {:02X?} {heat:?} (broadcast, answered: {})",
        &buf[..n],
        heat.command().broadcast.answered
    );

    // A value that does not fit its wire field (the set point travels as a u16) is refused
    // before it reaches the bus.
    let frost = Request::SetSetpoint(own_protocol::thermo::request::SetSetpoint {
        setpoint: DeciCelsius::from_value(-1.0).ok_or("not a whole number of tenths")?,
    });
    match frost.encode(0x01, &mut buf) {
        Err(e) => println!("encode   {frost:?}: {e}"),
        Ok(n) => return Err(format!("a negative set point encoded: {:02X?}", &buf[..n]).into()),
    }

    // One damaged byte: the error says what and where.
    let mut damaged = rx;
    damaged[4] ^= 0x01;
    match Response::decode(&damaged) {
        Err(e @ DecodeError::ChecksumMismatch { .. }) => println!("damaged  {e}"),
        other => return Err(format!("a damaged frame decoded: {other:?}").into()),
    }
    Ok(())
}
