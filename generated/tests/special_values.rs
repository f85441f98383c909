//! Constants for `special:` values (issue 26): each special value of a field is a typed
//! constant of its message's struct (`pelco_d::request::Standard::PAN_SPEED_TURBO`), which
//! encodes to the special byte and decodes back to itself. Frames from the specs' examples.

use busspec_protocols::{pelco_d, sd};

#[test]
fn pelco_d_turbo_speeds_encode_to_their_bytes_and_decode_back() {
    use pelco_d::request::Standard;
    assert_eq!(Standard::PAN_SPEED_TURBO, 0xFF);
    assert_eq!(Standard::PAN_SPEED_TURBO_40, 0x40);
    // "Pan left at turbo speed" and C466M-E's "Left, Turbo Speed".
    for (speed, frame) in [
        (
            Standard::PAN_SPEED_TURBO,
            [0xFF, 0x01, 0x00, 0x04, 0xFF, 0x00, 0x04],
        ),
        (
            Standard::PAN_SPEED_TURBO_40,
            [0xFF, 0x01, 0x00, 0x04, 0x40, 0x00, 0x45],
        ),
    ] {
        let pelco_d::Request::Standard(decoded) = pelco_d::Request::decode(&frame).unwrap().message
        else {
            panic!("{frame:02X?} is not a standard command");
        };
        assert_eq!(decoded.pan_speed, speed);
        assert!(decoded.pan_left);
        let m = Standard {
            pan_speed: speed,
            ..decoded
        };
        let mut buf = [0u8; pelco_d::MAX_FRAME_LEN];
        let n = m.encode(0x01, &mut buf).unwrap();
        assert_eq!(buf[..n], frame);
    }
}

#[test]
fn pelco_d_preset_specials_are_go_to_presets() {
    use pelco_d::request::GoToPreset;
    assert_eq!(GoToPreset::PRESET_FLIP, 0x21);
    assert_eq!(GoToPreset::PRESET_ZERO_PAN, 0x22);
    let m = GoToPreset {
        preset: GoToPreset::PRESET_FLIP,
    };
    let mut buf = [0u8; pelco_d::MAX_FRAME_LEN];
    let n = m.encode(0x01, &mut buf).unwrap();
    assert_eq!(buf[..n][4..6], [0x00, 0x21]);
    let d = pelco_d::Request::decode(&buf[..n]).unwrap();
    assert_eq!(d.message, pelco_d::Request::GoToPreset(m));
}

#[test]
fn sd_temperature_specials_encode_to_their_bytes_and_decode_back() {
    use sd::response::Temperatures;
    assert_eq!(Temperatures::MOTOR_TEMPERATURE_NO_SENSOR.raw(), 0x00);
    assert_eq!(Temperatures::PCB_TEMPERATURE_DEFECTIVE.raw(), 0xFF);
    // "motor: no sensor (raw 0x00, -50 °C); PCB: sensor defective (raw 0xFF, 205 °C)".
    let frame = [0x20, 0x01, 0x00, 0xFF, 0x02, 0x3D];
    let m = Temperatures {
        motor_temperature: Temperatures::MOTOR_TEMPERATURE_NO_SENSOR,
        pcb_temperature: Temperatures::PCB_TEMPERATURE_DEFECTIVE,
    };
    let mut buf = [0u8; sd::MAX_FRAME_LEN];
    let n = m.encode(0x01, &mut buf).unwrap();
    assert_eq!(buf[..n], frame);
    let d = sd::Response::decode(&frame).unwrap();
    assert_eq!(d.message, sd::Response::Temperatures(m));
}
