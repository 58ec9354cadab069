"""Loads a gleaner `QGC WPL 110` file with pymavlink's MAVWPLoader (the loader MAVProxy and
other pymavlink tools use) and checks every item against the mission document.

usage: check_wpl.py MISSION.waypoints MISSION.json
"""

import math
import os
import sys

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavwp  # noqa: E402

import expect  # noqa: E402
from expect import need  # noqa: E402


def check(argv):
    path, mission_path = argv
    mission = expect.load_json(mission_path)
    profile = mission["profile"]
    loader = mavwp.MAVWPLoader()
    n = loader.load(path)
    need(n == len(mission["stops"]) + 4, f"{n} items loaded, expected {len(mission['stops']) + 4}")
    wps = [loader.wp(k) for k in range(n)]
    for k, w in enumerate(wps):
        need(w.seq == k, f"item {k} has seq {w.seq}")
        need(w.autocontinue == 1, f"item {k} does not auto-continue")
    home = wps[0]
    need((home.command, home.frame, home.current) == (expect.NAV_WAYPOINT, expect.FRAME_GLOBAL, 1),
         f"home line: command {home.command}, frame {home.frame}, current {home.current}")
    need(expect.distance_m([home.y, home.x], profile["base_lon_lat"]) < expect.MAX_OFFSET_M,
         "home is not at the base")
    need(home.z == profile["base_alt_m"], f"home altitude {home.z} != {profile['base_alt_m']} m AMSL")
    items = [
        dict(command=w.command, frame=w.frame, p1=w.param1, p2=w.param2, p3=w.param3,
             p4=w.param4, lat=w.x, lon=w.y, alt=w.z)
        for w in wps[1:]
    ]
    expect.check_items(mission, items, "pymavlink")
    need(all(w.current == 0 for w in wps[1:]), "an item after home is marked current")
    speed = next(it for it in items if it["command"] == expect.DO_CHANGE_SPEED)
    need(not math.isnan(speed["p4"]), "DO_CHANGE_SPEED param4 is NaN")
    return f"pymavlink MAVWPLoader read {n} items from {os.path.basename(path)} " \
           f"({len(mission['stops'])} stops, {profile['cruise_speed_mps']} m/s)"


if __name__ == "__main__":
    expect.main(check, sys.argv[1:])
