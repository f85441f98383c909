"""MAVLink v1 frames made by pymavlink (an independent implementation), for the examples of
model/tests/fixtures/valid/mavlink_v1.yaml: each line is the message, its frame in hex and the
header values it was given. Run with pymavlink installed (2.4.50 made the fixture's frames):
    python3 -m venv /tmp/mav && /tmp/mav/bin/pip install pymavlink
    /tmp/mav/bin/python tests/reference/mavlink_v1_frames.py
"""
import os, io
os.environ.pop('MAVLINK20', None)
os.environ['MAVLINK_DIALECT'] = 'common'
os.environ['WIRE_PROTOCOL_VERSION'] = '1.0'
from pymavlink.dialects.v10 import common as mav
import pymavlink
print("pymavlink", pymavlink.__version__ if hasattr(pymavlink,'__version__') else '?')
f = io.BytesIO()
m = mav.MAVLink(f, srcSystem=1, srcComponent=1)
def show(name, msg, seq=None, sysid=None, compid=None):
    if sysid is not None: m.srcSystem = sysid
    if compid is not None: m.srcComponent = compid
    if seq is not None: m.seq = seq
    b = msg.pack(m)
    m.seq = (m.seq + 1) % 256
    print(name, ' '.join('%02X' % x for x in b), 'seq', b[2], 'sys', b[3], 'comp', b[4], 'id', b[5])
show('heartbeat', mav.MAVLink_heartbeat_message(2, 3, 0x51, 0, 4, 3), seq=0, sysid=1, compid=1)
show('heartbeat', mav.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3), seq=17, sysid=255, compid=190)
show('ping', mav.MAVLink_ping_message(1000000, 7, 1, 1), seq=5, sysid=255, compid=190)
show('ping_reply', mav.MAVLink_ping_message(1000000, 7, 255, 190), seq=42, sysid=1, compid=1)
show('sys_status', mav.MAVLink_sys_status_message(0x0020FC2F, 0x0020FC2F, 0x0020FC2F, 250, 12150, 830, 87, 0, 3, 0, 0, 0, 0), seq=200, sysid=1, compid=1)
show('attitude', mav.MAVLink_attitude_message(123456, 0.0625, -0.125, 1.5, 0.5, -0.03125, 0.25), seq=255, sysid=1, compid=1)
print(mav.MAVLink_heartbeat_message.crc_extra, mav.MAVLink_ping_message.crc_extra, mav.MAVLink_sys_status_message.crc_extra, mav.MAVLink_attitude_message.crc_extra)
print(mav.MAVLink_sys_status_message.ordered_fieldnames, mav.MAVLink_sys_status_message.fieldtypes)
print(mav.MAVLink_attitude_message.ordered_fieldnames)
print(mav.MAVLink_heartbeat_message.ordered_fieldnames)
print(mav.MAVLink_ping_message.ordered_fieldnames)
show('request_data_stream', mav.MAVLink_request_data_stream_message(1, 1, 0, 4, 1), seq=6, sysid=255, compid=190)
print(mav.MAVLink_request_data_stream_message.crc_extra, mav.MAVLink_request_data_stream_message.ordered_fieldnames)
