"""What a gleaner flight file must command, computed from the mission document itself
(gleaner.mission version 1, JSON) so that the checks do not trust the writer's own logic.

Shared by check_wpl.py, check_plan.py and check_geojson.py.
"""

import json
import math
import struct
import sys

# MAVLink ids (common.xml).
NAV_WAYPOINT = 16
NAV_RETURN_TO_LAUNCH = 20
NAV_TAKEOFF = 22
DO_CHANGE_SPEED = 178
FRAME_GLOBAL = 0
FRAME_MISSION = 2
FRAME_GLOBAL_RELATIVE_ALT = 3

# Largest distance between a written position and the planned one, m.
MAX_OFFSET_M = 0.1


class CheckFailed(Exception):
    """A consumer read something other than what the mission plans."""


def need(cond, message):
    """Fails the check with `message` unless `cond` holds (not an assert: survives -O)."""
    if not cond:
        raise CheckFailed(message)


def load_json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def distance_m(lon_lat_a, lon_lat_b):
    """Great-circle distance between two [lon, lat] in degrees, m (haversine)."""
    r = 6371008.8
    p1, p2 = math.radians(lon_lat_a[1]), math.radians(lon_lat_b[1])
    dp = p2 - p1
    dl = math.radians(lon_lat_b[0] - lon_lat_a[0])
    h = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
    return 2 * r * math.asin(min(1.0, math.sqrt(h)))


def f32(x):
    """x as a MAVLink float32 would store it."""
    return struct.unpack("f", struct.pack("f", x))[0]


def close(a, b, rel=1e-6):
    """Equal within `rel` relative (float32 fields carry ~7 digits)."""
    return a == b or abs(a - b) <= rel * max(abs(a), abs(b))


HOLD_STEP_S = 0.25


def check_hold(hold, hover_s, what):
    """A hold (s) covers the planned hover, exceeds it by less than the 0.25 s rounding and is
    a multiple of 0.25 s (exact as a float32)."""
    need(hold >= hover_s, f"{what}: hold {hold} s < planned hover {hover_s} s")
    need(f32(hold) == hold, f"{what}: hold {hold} s is not exact as a float32")
    need(hold < hover_s + HOLD_STEP_S, f"{what}: hold {hold} s >= hover {hover_s} s + 0.25 s")
    need(hold / HOLD_STEP_S == int(hold / HOLD_STEP_S), f"{what}: hold {hold} s not on 0.25 s")


def expected_sequence(mission):
    """(command, frame) of the items after home: take-off, speed, one waypoint per stop, RTL;
    for a continuation re-planned in the air, no take-off: speed, a waypoint where the
    aircraft is, one per stop, RTL."""
    if mission.get("continuation"):
        seq = [(DO_CHANGE_SPEED, FRAME_MISSION), (NAV_WAYPOINT, FRAME_GLOBAL_RELATIVE_ALT)]
    else:
        seq = [(NAV_TAKEOFF, FRAME_GLOBAL_RELATIVE_ALT), (DO_CHANGE_SPEED, FRAME_MISSION)]
    seq += [(NAV_WAYPOINT, FRAME_GLOBAL_RELATIVE_ALT)] * len(mission["stops"])
    seq.append((NAV_RETURN_TO_LAUNCH, FRAME_MISSION))
    return seq


def check_items(mission, items, source, yaw_nan=True):
    """Checks the items after home. Each item is a dict with command, frame, p1..p4 (floats),
    lat, lon (degrees) and alt (m)."""
    profile = mission["profile"]
    seq = [(it["command"], it["frame"]) for it in items]
    need(seq == expected_sequence(mission),
         f"{source}: (command, frame) sequence {seq} != {expected_sequence(mission)}")
    continuation = mission.get("continuation")
    if continuation:
        speed, start, *waypoints, rtl = items
        need(distance_m([start["lon"], start["lat"]], continuation["start_lon_lat"]) < MAX_OFFSET_M,
             f"{source}: the first waypoint is not where the aircraft is")
        need(start["p1"] == 0.0, f"{source}: the first waypoint holds {start['p1']} s, not 0")
        need(close(start["alt"], profile["altitude_m"]),
             f"{source}: first waypoint altitude {start['alt']} != {profile['altitude_m']}")
    else:
        take_off, speed, *waypoints, rtl = items
        need(distance_m([take_off["lon"], take_off["lat"]], profile["base_lon_lat"]) < MAX_OFFSET_M,
             f"{source}: take-off not at the base")
        need(close(take_off["alt"], profile["altitude_m"]),
             f"{source}: take-off altitude {take_off['alt']} != {profile['altitude_m']}")
    need(speed["p1"] == 1.0, f"{source}: DO_CHANGE_SPEED speed type {speed['p1']} != 1 (ground)")
    need(close(speed["p2"], profile["cruise_speed_mps"]),
         f"{source}: DO_CHANGE_SPEED speed {speed['p2']} != {profile['cruise_speed_mps']} m/s")
    need(speed["p3"] == -1.0, f"{source}: DO_CHANGE_SPEED throttle {speed['p3']} != -1")
    for stop, wp in zip(mission["stops"], waypoints):
        what = f"{source}: stop {stop['order']} ({stop['cell']})"
        d = distance_m([wp["lon"], wp["lat"]], stop["centre_lon_lat"])
        need(d < MAX_OFFSET_M, f"{what}: waypoint {d:.4f} m from the cell centre")
        need(close(wp["alt"], profile["altitude_m"]),
             f"{what}: altitude {wp['alt']} != {profile['altitude_m']} m above home")
        check_hold(wp["p1"], stop["hover_s"], what)
        if yaw_nan:
            need(math.isnan(wp["p4"]), f"{what}: yaw {wp['p4']} is not NaN")
    need(all(rtl[k] == 0 for k in ("p1", "p2", "p3", "p4")), f"{source}: RTL has parameters")


def main(check, argv):
    """Runs check(argv); prints one line; exit status 1 on a failed check."""
    try:
        summary = check(argv)
    except CheckFailed as e:
        print(f"FAILED {argv[0] if argv else ''}: {e}", file=sys.stderr)
        sys.exit(1)
    print(f"ok: {summary}")
