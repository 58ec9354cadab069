"""A stand-in vehicle for mavsdk_server, which only serves its API once it has discovered a
MAVLink system: a thread that sends HEARTBEATs from system 1, component 1 to a loopback UDP
port and acknowledges every COMMAND_LONG/COMMAND_INT with MAV_RESULT_UNSUPPORTED (so MAVSDK's
requests for AUTOPILOT_VERSION etc. end at once instead of timing out). Nothing leaves
127.0.0.1 and the thread stops with the `with` block.
"""

import os
import socket
import threading
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

AUTOPILOTS = {
    "px4": mavutil.mavlink.MAV_AUTOPILOT_PX4,
    "ardupilot": mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
}


def free_port(kind):
    """A loopback port free right now (UDP or TCP)."""
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class FakeVehicle:
    """`with FakeVehicle("px4") as v:` then connect MAVSDK to `v.mavsdk_address`."""

    def __init__(self, autopilot="px4"):
        self.autopilot = AUTOPILOTS[autopilot]
        self.port = free_port(socket.SOCK_DGRAM)
        self.mavsdk_address = f"udpin://127.0.0.1:{self.port}"
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self.received = {}

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join(timeout=5)

    def _run(self):
        link = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{self.port}", source_system=1, source_component=1)
        try:
            deadline = time.monotonic() + 120  # bounded even if never stopped
            next_beat = 0.0
            while not self._stop.is_set() and time.monotonic() < deadline:
                now = time.monotonic()
                if now >= next_beat:
                    link.mav.heartbeat_send(
                        mavutil.mavlink.MAV_TYPE_QUADROTOR, self.autopilot, 0, 0,
                        mavutil.mavlink.MAV_STATE_STANDBY)
                    next_beat = now + 0.25
                msg = link.recv_match(blocking=True, timeout=0.05)
                if msg is None:
                    continue
                kind = msg.get_type()
                self.received[kind] = self.received.get(kind, 0) + 1
                if kind in ("COMMAND_LONG", "COMMAND_INT"):
                    link.mav.command_ack_send(
                        msg.command, mavutil.mavlink.MAV_RESULT_UNSUPPORTED, 0, 0,
                        msg.get_srcSystem(), msg.get_srcComponent())
        finally:
            link.close()
