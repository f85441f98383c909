"""MAVLink v2 frames made by pymavlink (an independent implementation), for the examples of
model/tests/fixtures/valid/mavlink_v2.yaml: each line is the message, its frame in hex and the
header values it was given. pymavlink strips every v2 payload's trailing zero bytes (keeping
one), so most of these frames are truncated. Run with pymavlink installed (2.4.50 made the
fixture's frames), e.g. in the venv tests/reference/check.sh makes:
    target/reference-venv/bin/python tests/reference/mavlink_v2_frames.py
"""
import io
import os

os.environ['MAVLINK20'] = '1'
os.environ['MAVLINK_DIALECT'] = 'common'
from pymavlink.dialects.v20 import common as mav  # noqa: E402

f = io.BytesIO()
m = mav.MAVLink(f, srcSystem=1, srcComponent=1)


def show(name, msg, seq, sysid, compid):
    m.srcSystem, m.srcComponent, m.seq = sysid, compid, seq
    b = msg.pack(m)
    print(name, ' '.join('%02X' % x for x in b), '| len', b[1], 'of', msg.unpacker.size,
          'seq', b[4], 'sys', b[5], 'comp', b[6], 'id', b[7] | b[8] << 8 | b[9] << 16)


show('heartbeat', mav.MAVLink_heartbeat_message(2, 3, 0x51, 0, 4, 3), 0, 1, 1)
show('heartbeat', mav.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3), 17, 255, 190)
show('ping', mav.MAVLink_ping_message(1000000, 7, 1, 1), 5, 255, 190)
show('ping_reply', mav.MAVLink_ping_message(1000000, 7, 255, 190), 42, 1, 1)
show('ping_zero', mav.MAVLink_ping_message(0, 0, 0, 0), 9, 255, 190)
show('sys_status', mav.MAVLink_sys_status_message(
    0x0020FC2F, 0x0020FC2F, 0x0020FC2F, 250, 12150, 830, 87, 0, 3, 0, 0, 0, 0), 200, 1, 1)
show('sys_status_ext', mav.MAVLink_sys_status_message(
    0x0020FC2F, 0x0020FC2F, 0x0020FC2F, 250, 12150, 830, 87, 0, 3, 0, 0, 0, 0, 1, 1, 1), 201, 1, 1)
show('attitude', mav.MAVLink_attitude_message(123456, 0.0625, -0.125, 1.5, 0.5, -0.03125, 0.25), 255, 1, 1)
show('attitude_zero_rates', mav.MAVLink_attitude_message(123456, 0.0625, -0.125, 1.5, 0, 0, 0), 3, 1, 1)
show('request_data_stream', mav.MAVLink_request_data_stream_message(1, 1, 0, 4, 1), 6, 255, 190)
show('request_data_stream_stop', mav.MAVLink_request_data_stream_message(1, 1, 0, 4, 0), 7, 255, 190)
show('attitude_quaternion', mav.MAVLink_attitude_quaternion_message(
    123456, 0.5, -0.5, 0.25, 0.75, 0.0625, -0.125, 1.5, [0, 0, 0, 0]), 12, 1, 1)
show('attitude_quaternion_offset', mav.MAVLink_attitude_quaternion_message(
    123456, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, [0.5, 0.5, -0.5, 0.5]), 13, 1, 1)
show('raw_rpm', mav.MAVLink_raw_rpm_message(2, 1500.5), 77, 1, 1)
show('raw_rpm_first', mav.MAVLink_raw_rpm_message(0, 1500.5), 78, 1, 1)
for c in (mav.MAVLink_heartbeat_message, mav.MAVLink_sys_status_message, mav.MAVLink_ping_message,
          mav.MAVLink_attitude_message, mav.MAVLink_attitude_quaternion_message,
          mav.MAVLink_request_data_stream_message,
          mav.MAVLink_raw_rpm_message):
    print(c.id, c.msgname, c.crc_extra, c.ordered_fieldnames, c.unpacker.format)
