"""Checks a gleaner DJI WPML archive (mission.kmz): both documents parse with lxml, their KML
parts (every element outside DJI's `wpml` namespace) validate against the OGC KML 2.2 schema
as the `fastkml` package ships it, and the waylines and the template command the mission
document's waypoints (lon, lat order), speed, height and holds.

usage: check_kml.py MISSION.kmz MISSION.json
"""

import os
import sys
import zipfile

from fastkml import validator
from lxml import etree

import expect
from expect import need

KML_NS = "http://www.opengis.net/kml/2.2"
WPML_NS = "http://www.dji.com/wpmz/1.0.2"
ENTRIES = ("wpmz/template.kml", "wpmz/waylines.wpml")


def kml_part(root):
    """A copy of the document without DJI's extension elements and attributes."""
    copy = etree.fromstring(etree.tostring(root))
    for el in list(copy.iter(f"{{{WPML_NS}}}*")):
        el.getparent().remove(el)
    etree.cleanup_namespaces(copy)
    return copy


def wpml(el, name):
    found = el.find(f"{{{WPML_NS}}}{name}")
    return None if found is None else found.text.strip()


def waypoints(root):
    """(lon, lat, height, speed, hover) of every Placemark."""
    out = []
    for pm in root.iter(f"{{{KML_NS}}}Placemark"):
        lon, lat = (float(x) for x in pm.find(f".//{{{KML_NS}}}coordinates").text.strip().split(",")[:2])
        height = wpml(pm, "executeHeight") or wpml(pm, "height")
        hover = sum(
            float(a.find(f".//{{{WPML_NS}}}hoverTime").text)
            for a in pm.iter(f"{{{WPML_NS}}}action")
            if wpml(a, "actionActuatorFunc") == "hover"
        )
        out.append((lon, lat, float(height), float(wpml(pm, "waypointSpeed")), hover))
    return out


def check(argv):
    path, mission_path = argv
    mission = expect.load_json(mission_path)
    profile = mission["profile"]
    schema = validator.get_schema_parser()
    with zipfile.ZipFile(path) as z:
        need(sorted(z.namelist()) == sorted(ENTRIES), f"entries {z.namelist()}")
        for name in ENTRIES:
            root = etree.fromstring(z.read(name))
            need(root.tag == f"{{{KML_NS}}}kml", f"{name}: root {root.tag}")
            part = kml_part(root)
            need(schema.validate(part), f"{name}: KML 2.2 schema: {schema.error_log}")
            wps = waypoints(root)
            plan = expect.flown(mission)
            need(len(wps) == len(plan), f"{name}: {len(wps)} waypoints, expected {len(plan)}")
            for k, ((lon_lat, stop), (lon, lat, height, speed, hover)) in enumerate(zip(plan, wps)):
                what = (f"{name}: stop {stop['order']} ({stop['cell']})" if stop
                        else f"{name}: turn point {k}")
                d = expect.distance_m([lon, lat], lon_lat)
                need(d < expect.MAX_OFFSET_M, f"{what}: waypoint {d:.4f} m from the plan")
                need(height == profile["altitude_m"], f"{what}: height {height} m")
                need(abs(speed - profile["cruise_speed_mps"]) <= 0.125,
                     f"{what}: speed {speed} m/s for a planned {profile['cruise_speed_mps']} m/s")
                if stop:
                    expect.check_hold(hover, stop["hover_s"], what)
                else:
                    need(hover == 0, f"{what}: a turn point hovers {hover} s")
    return f"lxml parsed {os.path.basename(path)}; its KML parts validate against OGC KML 2.2 " \
           f"(fastkml's schema); {len(mission['stops'])} waypoints with speeds, heights and holds"


if __name__ == "__main__":
    expect.main(check, sys.argv[1:])
