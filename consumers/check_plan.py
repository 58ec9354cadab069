"""Imports a gleaner QGroundControl `.plan` with MAVSDK's QGC importer
(`mission_raw.import_qgroundcontrol_mission`, run by the mavsdk_server bundled with
MAVSDK-Python) and checks the imported items against the mission document; optionally also
imports the `QGC WPL 110` file with MAVSDK's Mission Planner importer.

mavsdk_server serves its API only once it sees a vehicle, so a fake one (fake_vehicle.py)
sends HEARTBEATs on loopback. The plan is imported twice: as for a PX4 vehicle (mission items
only) and as for an ArduPilot vehicle (MAVSDK inserts `plannedHomePosition` as item 0).

usage: check_plan.py MISSION.plan MISSION.json [MISSION.waypoints]
"""

import asyncio
import math
import os
import socket
import sys

from mavsdk import System

import expect
from expect import need
from fake_vehicle import FakeVehicle, free_port

TIMEOUT_S = 60


def as_item(it):
    """A MAVSDK MissionItem as the dict expect.check_items takes (lat/lon from degE7)."""
    return dict(command=it.command, frame=it.frame, p1=it.param1, p2=it.param2, p3=it.param3,
                p4=it.param4, lat=it.x / 1e7, lon=it.y / 1e7, alt=it.z)


async def import_with(autopilot, plan_path, wpl_path):
    """Imports the files through a mavsdk_server connected to a fake `autopilot` vehicle."""
    with FakeVehicle(autopilot) as vehicle:
        drone = System(port=free_port(socket.SOCK_STREAM))
        try:
            await drone.connect(system_address=vehicle.mavsdk_address)
            async for state in drone.core.connection_state():
                if state.is_connected:
                    break
            plan = await drone.mission_raw.import_qgroundcontrol_mission(plan_path)
            wpl = None
            if wpl_path:
                wpl = await drone.mission_raw.import_mission_planner_mission(wpl_path)
            return plan, wpl
        finally:
            drone._stop_mavsdk_server()


def check_plan_items(mission, items, source):
    n = len(expect.flown(mission)) + 3
    need(len(items) == n, f"{source}: {len(items)} mission items, expected {n}")
    for k, it in enumerate(items):
        need(it.seq == k, f"{source}: item {k} has seq {it.seq}")
        need(it.autocontinue == 1, f"{source}: item {k} does not auto-continue")
        need(it.mission_type == 0, f"{source}: item {k} is not a mission item")
    expect.check_items(mission, [as_item(it) for it in items], source)


def check_home(mission, home, source):
    profile = mission["profile"]
    need((home.command, home.seq) == (expect.NAV_WAYPOINT, 0),
         f"{source}: item 0 is not the home waypoint")
    d = expect.distance_m([home.y / 1e7, home.x / 1e7], profile["base_lon_lat"])
    need(d < expect.MAX_OFFSET_M, f"{source}: home {d:.3f} m from the base")
    need(expect.close(home.z, profile["base_alt_m"]),
         f"{source}: home altitude {home.z} != {profile['base_alt_m']} m AMSL")


# MAV_CMD_NAV_FENCE_*: polygon vertex (inclusion, exclusion), circle (inclusion, exclusion).
FENCE_POLYGON = {True: 5001, False: 5002}
FENCE_CIRCLE = {True: 5003, False: 5004}


def check_fence(fence, items, source):
    """The geoFence MAVSDK imported: one fence item (mission type 1) per polygon vertex, with the
    polygon's kind (inclusion / exclusion) and vertex count, at the plan's positions, then one
    per circle; nothing without zones."""
    need(fence.get("version") == 2, f"{source}: geoFence version {fence.get('version')}")
    want = []
    for p in fence["polygons"]:
        for lat, lon in p["polygon"]:
            want.append((FENCE_POLYGON[p["inclusion"]], len(p["polygon"]), lat, lon))
    for c in fence["circles"]:
        lat, lon = c["circle"]["center"]
        want.append((FENCE_CIRCLE[c["inclusion"]], c["circle"]["radius"], lat, lon))
    need(len(items) == len(want), f"{source}: {len(items)} fence items, expected {len(want)}")
    for k, (it, (command, p1, lat, lon)) in enumerate(zip(items, want)):
        need(it.mission_type == 1, f"{source}: fence item {k} has mission type {it.mission_type}")
        need(it.command == command, f"{source}: fence item {k} command {it.command} != {command}")
        need(expect.close(it.param1, p1), f"{source}: fence item {k} param1 {it.param1} != {p1}")
        d = expect.distance_m([it.y / 1e7, it.x / 1e7], [lon, lat])
        need(d < expect.MAX_OFFSET_M, f"{source}: fence item {k} is {d:.3f} m off")


def check(argv):
    plan_path, mission_path, *rest = argv
    wpl_path = rest[0] if rest else None
    mission = expect.load_json(mission_path)
    plan_json = expect.load_json(plan_path)
    speed = mission["profile"]["cruise_speed_mps"]
    need(plan_json["mission"]["cruiseSpeed"] == speed, "cruiseSpeed is not the planned speed")
    need(plan_json["mission"]["hoverSpeed"] == speed, "hoverSpeed is not the planned speed")
    need(plan_json["mission"]["plannedHomePosition"][2] == mission["profile"]["base_alt_m"],
         "plannedHomePosition altitude is not the base altitude AMSL")
    meta = plan_json.get("gleaner", {})
    for key in ("mission_id", "kind", "planned_at", "cruise_speed_mps", "altitude_m"):
        want = mission["profile"].get(key, mission.get(key))
        need(meta.get(key) == want, f"plan metadata {key} = {meta.get(key)!r}, expected {want!r}")
    need(meta.get("energy") == mission["energy"], "plan metadata energy != the mission's")

    px4, px4_wpl = asyncio.run(asyncio.wait_for(
        import_with("px4", plan_path, wpl_path), TIMEOUT_S))
    check_plan_items(mission, px4.mission_items, "MAVSDK QGC import (PX4)")
    need(not px4.rally_items, "MAVSDK imported rally points")
    check_fence(plan_json["geoFence"], px4.geofence_items, "MAVSDK QGC import (PX4)")

    ardu, _ = asyncio.run(asyncio.wait_for(import_with("ardupilot", plan_path, None), TIMEOUT_S))
    items = ardu.mission_items
    need(len(items) == len(px4.mission_items) + 1, "MAVSDK (ArduPilot) did not insert home")
    check_home(mission, items[0], "MAVSDK QGC import (ArduPilot)")
    renumbered = items[1:]
    expect.check_items(mission, [as_item(it) for it in renumbered], "MAVSDK QGC import (ArduPilot)")

    done = f"MAVSDK imported {len(px4.mission_items)} items from {os.path.basename(plan_path)}"
    if px4_wpl is not None:
        w = px4_wpl.mission_items
        need(len(w) == len(expect.flown(mission)) + 4,
             f"MAVSDK Mission Planner import: {len(w)} items, expected {len(expect.flown(mission)) + 4}")
        check_home(mission, w[0], "MAVSDK Mission Planner import")
        expect.check_items(mission, [as_item(it) for it in w[1:]], "MAVSDK Mission Planner import")
        need(all(math.isnan(it.param4) for it in w[1:] if it.command != expect.DO_CHANGE_SPEED
                 and it.command != expect.NAV_RETURN_TO_LAUNCH),
             "MAVSDK Mission Planner import: yaw not NaN")
        done += f" and {len(w)} from {os.path.basename(wpl_path)}"
    return done + f" (commands incl. DO_CHANGE_SPEED {speed} m/s)"


if __name__ == "__main__":
    expect.main(check, sys.argv[1:])
