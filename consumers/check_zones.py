"""Checks with shapely that no exported flight path touches a no-fly zone or leaves the
geofence: the zones as the mission document gives them (`zones`: as the settings' GeoJSON
files give them, without the planner's safety buffer), the paths as each file commands them,
read back from the file itself.

usage: check_zones.py MISSION.json FILE... (any of .plan, .waypoints, .geojson, .kmz)

Paths: the `.plan`'s mission items (plannedHomePosition, every NAV_WAYPOINT, back home on
RTL), the WPL's lines (home line 0, every NAV_WAYPOINT, home), the GeoJSON's `route`
LineString, the KMZ's `wpmz/waylines.wpml` Placemarks (from and back to the base). Each path
must not intersect (touching counts) any no-fly zone — polygon, line or point — and must lie
inside the union of the geofence's polygons, if there is one. The `.plan`'s `geoFence` and the
GeoJSON's zone features must carry the document's zones. Positions are WGS84 [lon, lat]
degrees; at a farm's scale the planar test in degrees is the test in metres up to an affine
map (the buffer, metres, is far above the difference).
"""

import os
import sys
import zipfile

from lxml import etree
from shapely.geometry import LineString, Point, Polygon
from shapely.ops import unary_union

import expect
from expect import need

KML_NS = "http://www.opengis.net/kml/2.2"


def zone_shapes(mission):
    """(no-fly shapes with a label, geofence union or None) from the mission document."""
    no_fly, fence = [], []
    for z in mission.get("zones", []):
        label = f"{z['kind']} zone {z['feature']}" + (f" ({z['name']})" if z.get("name") else "")
        parts = [Polygon(p[0], p[1:]) for p in z.get("polygons_lon_lat", [])]
        for line in z.get("lines_lon_lat", []):
            parts.append(Point(line[0]) if len(line) == 1 else LineString(line))
        for shape in parts:
            need(shape.is_valid, f"{label}: shapely says invalid")
            if z["kind"] == "geofence":
                fence.append(shape)
            else:
                need(z["kind"] == "no-fly", f"{label}: unknown kind")
                no_fly.append((label, shape))
    return no_fly, (unary_union(fence) if fence else None)


def plan_path(path):
    plan = expect.load_json(path)
    lat, lon, _ = plan["mission"]["plannedHomePosition"]
    home = (lon, lat)
    pts = [home]
    for it in plan["mission"]["items"]:
        if it["command"] == expect.NAV_WAYPOINT:
            pts.append((it["params"][5], it["params"][4]))
        elif it["command"] == expect.NAV_RETURN_TO_LAUNCH:
            pts.append(home)
    return pts, plan["geoFence"]


def wpl_path(path):
    with open(path, encoding="utf-8") as f:
        rows = [line.split("\t") for line in f.read().splitlines()[1:] if line.strip()]
    home = (float(rows[0][9]), float(rows[0][8]))
    pts = [home]
    for r in rows[1:]:
        if int(r[3]) == expect.NAV_WAYPOINT:
            pts.append((float(r[9]), float(r[8])))
        elif int(r[3]) == expect.NAV_RETURN_TO_LAUNCH:
            pts.append(home)
    return pts


def geojson_path(path):
    doc = expect.load_json(path)
    routes = [f for f in doc["features"] if f["properties"].get("kind") == "route"]
    need(len(routes) == 1, f"{path}: {len(routes)} routes")
    zones = [f for f in doc["features"] if f["properties"].get("kind") in ("geofence", "no-fly")]
    return [tuple(p) for p in routes[0]["geometry"]["coordinates"]], zones


def kmz_path(path, base):
    with zipfile.ZipFile(path) as z:
        root = etree.fromstring(z.read("wpmz/waylines.wpml"))
    pts = [tuple(base)]
    for pm in root.iter(f"{{{KML_NS}}}Placemark"):
        lon, lat = (float(x) for x in pm.find(f".//{{{KML_NS}}}coordinates").text.split(",")[:2])
        pts.append((lon, lat))
    pts.append(tuple(base))
    return pts


def check(argv):
    mission_path, *files = argv
    mission = expect.load_json(mission_path)
    no_fly, fence = zone_shapes(mission)
    need(no_fly or fence is not None, "the mission has no zones to check against")
    base = mission["profile"]["base_lon_lat"]
    checked, segments = [], 0
    for path in files:
        name = os.path.basename(path)
        ext = os.path.splitext(path)[1]
        if ext == ".plan":
            pts, geofence = plan_path(path)
            polygons = geofence["polygons"]
            want = sum(len(z.get("polygons_lon_lat", [])) for z in mission["zones"]
                       if z["kind"] == "no-fly")
            want += sum(len(p) for z in mission["zones"] if z["kind"] == "geofence"
                        for p in z.get("polygons_lon_lat", []))
            need(len(polygons) == want, f"{name}: {len(polygons)} geoFence polygons, expected {want}")
            need(all(p["inclusion"] is False for p in polygons) or fence is not None,
                 f"{name}: an inclusion polygon without a geofence")
        elif ext == ".waypoints":
            pts = wpl_path(path)
        elif ext == ".geojson":
            pts, zones = geojson_path(path)
            need(len(zones) == len(mission["zones"]),
                 f"{name}: {len(zones)} zone features, the mission has {len(mission['zones'])}")
        elif ext == ".kmz":
            pts = kmz_path(path, base)
        else:
            raise expect.CheckFailed(f"{name}: unknown file type")
        need(len(pts) >= 3, f"{name}: a path of {len(pts)} positions")
        route = LineString(pts)
        for label, zone in no_fly:
            if route.intersects(zone):
                bad = [k for k in range(len(pts) - 1) if LineString(pts[k:k + 2]).intersects(zone)]
                raise expect.CheckFailed(
                    f"{name}: the path crosses {label} on segment(s) {bad}")
        if fence is not None:
            need(fence.contains(route), f"{name}: the path leaves the geofence")
        segments += len(pts) - 1
        checked.append(name)
    turns = sum(len(s.get("via_lon_lat", [])) for s in mission["stops"])
    turns += len(mission.get("return_via_lon_lat", []))
    return (f"shapely: 0 intersections of {segments} path segments in {', '.join(checked)} "
            f"with {len(no_fly)} no-fly zone shapes" + (" and inside the geofence" if fence else "")
            + f" ({turns} turn points)")


if __name__ == "__main__":
    expect.main(check, sys.argv[1:])
