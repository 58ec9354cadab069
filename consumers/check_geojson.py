"""Checks a gleaner GeoJSON map with the `geojson` package (RFC 7946 validity) and shapely
(geometry validity, ring orientation), against the mission and field documents.

usage: check_geojson.py MISSION.geojson MISSION.json FIELD.json
"""

import os
import sys

import geojson
from shapely.geometry import shape

import expect
from expect import need


def check(argv):
    path, mission_path, field_path = argv
    mission = expect.load_json(mission_path)
    field = expect.load_json(field_path)
    with open(path, encoding="utf-8") as f:
        text = f.read()
    raw = expect.load_json(path)
    fc = geojson.loads(text)
    need(isinstance(fc, geojson.FeatureCollection), f"top level is {type(fc).__name__}")
    need(fc.is_valid, f"geojson says invalid: {fc.errors()}")
    need("crs" not in raw, "a `crs` member (RFC 7946 removed it)")

    by_kind = {}
    for feat in fc["features"]:
        need(isinstance(feat, geojson.Feature), f"member {type(feat).__name__} is not a Feature")
        need(feat.is_valid, f"feature {feat.get('id')}: {feat.errors()}")
        by_kind.setdefault(feat["properties"]["kind"], []).append(feat)

    # Cells: valid polygons, counter-clockwise exterior rings (RFC 7946 §3.1.6), scores and
    # visiting order as in the documents.
    cells = by_kind.get("cell", [])
    need(len(cells) == len(field["cells"]), f"{len(cells)} cells, field has {len(field['cells'])}")
    order = {s["cell"]: s["order"] for s in mission["stops"]}
    for feat, doc in zip(cells, field["cells"]):
        props = feat["properties"]
        need(props["cell"] == doc["cell"], f"cell {props['cell']} where {doc['cell']} expected")
        need(feat["geometry"]["type"] == "Polygon", f"cell {doc['cell']} is not a Polygon")
        poly = shape(feat["geometry"])
        need(poly.is_valid, f"cell {doc['cell']}: shapely says invalid")
        need(poly.area > 0, f"cell {doc['cell']}: empty polygon")
        need(poly.exterior.is_ccw, f"cell {doc['cell']}: exterior ring is clockwise")
        need(poly.contains(shape({"type": "Point", "coordinates": doc["centre_lon_lat"]})),
             f"cell {doc['cell']}: centre outside the polygon")
        need(props.get("visit_order") == order.get(doc["cell"]),
             f"cell {doc['cell']}: visit_order {props.get('visit_order')} != {order.get(doc['cell'])}")
        scores = doc.get("scores")
        for key in "SFRAU":
            want = scores[key.lower()] if scores else None
            need(props.get(key) == want, f"cell {doc['cell']}: {key} = {props.get(key)} != {want}")

    # The route: base (or, for a continuation, where the aircraft is) -> stops -> base.
    routes = by_kind.get("route", [])
    need(len(routes) == 1, f"{len(routes)} route features")
    route = routes[0]
    need(route["geometry"]["type"] == "LineString", "the route is not a LineString")
    line = shape(route["geometry"])
    need(line.is_valid, "the route: shapely says invalid")
    coords = list(route["geometry"]["coordinates"])
    base = mission["profile"]["base_lon_lat"]
    start = (mission.get("continuation") or {}).get("start_lon_lat", base)
    planned = [start] + [s["centre_lon_lat"] for s in mission["stops"]] + [base]
    need(len(coords) == len(planned), f"route has {len(coords)} positions, expected {len(planned)}")
    for k, (got, want) in enumerate(zip(coords, planned)):
        d = expect.distance_m(got, want)
        need(d < expect.MAX_OFFSET_M, f"route position {k} is {d:.3f} m from the plan")
    need(route["properties"]["cells"] == [s["cell"] for s in mission["stops"]],
         "route cells out of order")

    stops = by_kind.get("stop", [])
    need([s["properties"]["visit_order"] for s in stops] == [s["order"] for s in mission["stops"]],
         "stop points out of order")
    bases = by_kind.get("base", [])
    need(len(bases) == 1 and bases[0]["geometry"]["type"] == "Point", "no single base Point")
    need(expect.distance_m(bases[0]["geometry"]["coordinates"], base) < expect.MAX_OFFSET_M,
         "base Point is not at the base")
    sensors = by_kind.get("sensor", [])
    need(sorted(s["properties"]["sensor"] for s in sensors) == sorted(s["id"] for s in field["sensors"]),
         "sensor Points differ from the field's sensors")
    need(all(s["geometry"]["type"] == "Point" for s in sensors), "a sensor is not a Point")

    # The mission's assumptions as a foreign member.
    meta = raw.get("gleaner")
    need(isinstance(meta, dict), "no `gleaner` foreign member")
    for key in ("mission_id", "kind", "planned_at", "planned_at_s", "weights", "anomaly_form",
                "energy"):
        need(meta.get(key) == mission[key], f"metadata {key} = {meta.get(key)!r} != {mission[key]!r}")
    return (f"geojson+shapely accept {os.path.basename(path)}: {len(cells)} CCW cell polygons, "
            f"route of {len(coords)} positions, {len(sensors)} sensors ({meta['kind']})")


if __name__ == "__main__":
    expect.main(check, sys.argv[1:])
