// The messages of the bench subset, shared by `mixed.rs` and the flash-size crate
// (`benches/flash/build.rs`), which includes this file.

/// Every kind of UB2 frame: 1- and 2-byte codes, no payload to 11 ASCII bytes, u16/i16/u32
/// little-endian fields, an enum (both ways), a code shared by messages told apart by a
/// constant (0x4072), a setter and its echo ACK sharing a code (0x8000), NAKs.
pub const UB2_SUBSET: &[&str] = &[
    "reference_run",
    "go_to_capacitance",
    "go_to_capacitance_status",
    "go_to_full_step_position",
    "move_full_steps",
    "set_mode_of_operation",
    "get_actual_capacitance",
    "get_mode_of_operation",
    "get_c_curve_indexed_full_step_capacitance",
    "get_controller_temperature",
    "get_firmware_version",
    "get_lower_customer_limit",
    "get_upper_customer_limit",
    "movement_started",
    "movement_completed",
    "movement_not_completed",
    "nak_limit_reached",
    "nak_index_out_of_range",
    "set_mode_of_operation_ack",
    "actual_capacitance",
    "actual_mode_of_operation",
    "c_curve_entry",
    "controller_temperature",
    "firmware_version",
    "lower_customer_limit",
    "upper_customer_limit",
];

/// Every kind of SD frame: packed bit fields (a signed 12-bit position, a constant nibble),
/// signed 16-bit values, constant arguments, a repeated argument, codes shared by requests
/// told apart by a constant (0x40), special values, a flag set, and replies only their
/// request identifies (0x22).
pub const SD_SUBSET: &[&str] = &[
    "set_point",
    "read_actual_position",
    "set_velocity",
    "read_actual_velocity",
    "set_servo_id",
    "read_temperatures",
    "read_humidity",
    "read_actuator_status_word",
    "reset_actuator_status_word",
    "read_total_runtime_hours",
    "read_total_runtime_min_sec",
    "set_point_reply",
    "actual_position",
    "set_velocity_reply",
    "actual_velocity",
    "set_servo_id_reply",
    "temperatures",
    "humidity",
    "actuator_status_word",
    "total_runtime_hours",
    "total_runtime_min_sec",
];
