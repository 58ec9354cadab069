use super::*;
use geo::{Rect, coord};
use proptest::prelude::*;

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Geometry<f64> {
    Geometry::Polygon(Rect::new(coord! {x: x0, y: y0}, coord! {x: x1, y: y1}).to_polygon())
}

fn c(x: f64, y: f64) -> Coord<f64> {
    Coord { x, y }
}

fn opts(buffer_m: f64) -> AirspaceOptions {
    AirspaceOptions {
        buffer_m,
        ..AirspaceOptions::default()
    }
}

/// Every segment of the path a -> via -> b is clear and its length the sum of segments.
fn check_path(airspace: &Airspace, a: Coord<f64>, via: &[Coord<f64>], b: Coord<f64>, len: f64) {
    let pts: Vec<Coord<f64>> = std::iter::once(a)
        .chain(via.iter().copied())
        .chain(std::iter::once(b))
        .collect();
    let mut total = 0.0;
    for w in pts.windows(2) {
        assert!(
            airspace.segment_clear(w[0], w[1]),
            "segment {:?} -> {:?} is not clear",
            w[0],
            w[1]
        );
        total += dist(w[0], w[1]);
    }
    assert!(
        (total - len).abs() <= 1e-9 * len.max(1.0),
        "{total} vs {len}"
    );
}

#[test]
fn open_airspace_paths_are_straight() {
    let airspace = Airspace::new(&[], None, opts(5.0)).unwrap();
    assert!(airspace.is_open());
    let pts = [c(0.0, 0.0), c(3.0, 4.0), c(-10.0, 2.0)];
    let paths = airspace.paths(&pts);
    assert_eq!(paths.length_m(0, 1), Some(5.0));
    assert_eq!(paths.via(1, 2), Some(&[][..]));
}

#[test]
fn a_building_in_the_way_is_flown_around_and_one_off_the_line_is_not() {
    let building = rect(40.0, -10.0, 60.0, 10.0);
    let airspace = Airspace::new(&[building], None, opts(5.0)).unwrap();
    let pts = [c(0.0, 0.0), c(100.0, 0.0), c(0.0, 50.0), c(100.0, 50.0)];
    let paths = airspace.paths(&pts);
    let via = paths.via(0, 1).unwrap();
    assert_eq!(via.len(), 2, "{via:?}");
    // Around the corners of the building grown by 5 m + 0.5 m: y = ±15.5.
    for v in via {
        assert!((v.y.abs() - 15.5).abs() < 1e-6, "{v:?}");
    }
    let len = paths.length_m(0, 1).unwrap();
    check_path(&airspace, pts[0], via, pts[1], len);
    assert!(len > 100.0);
    // The reverse is the same path backwards, with the same length to the bit.
    let back: Vec<_> = paths.via(1, 0).unwrap().iter().rev().copied().collect();
    assert_eq!(back, via);
    assert_eq!(paths.length_m(1, 0).unwrap().to_bits(), len.to_bits());
    // Far above the building: straight.
    assert_eq!(paths.via(2, 3), Some(&[][..]));
    assert_eq!(paths.length_m(2, 3), Some(100.0));
    // A pair's path does not depend on the other points asked for.
    let two = airspace.paths(&[pts[1], pts[0]]);
    assert_eq!(two.via(1, 0).unwrap(), via);
}

#[test]
fn points_inside_a_zone_or_outside_the_fence_are_blocked() {
    let fence = MultiPolygon(vec![
        Rect::new(coord! {x: -100.0, y: -100.0}, coord! {x: 100.0, y: 100.0}).to_polygon(),
    ]);
    let airspace = Airspace::new(
        &[
            rect(10.0, 10.0, 20.0, 20.0),
            rect(-50.0, -50.0, -40.0, -40.0),
        ],
        Some(&fence),
        opts(5.0),
    )
    .unwrap();
    assert_eq!(
        airspace.blocked(c(15.0, 15.0)),
        Some(Blocked::NoFly { zone: 0 })
    );
    // Within the buffer of zone 1.
    assert_eq!(
        airspace.blocked(c(-37.0, -45.0)),
        Some(Blocked::NoFly { zone: 1 })
    );
    assert_eq!(airspace.blocked(c(0.0, 0.0)), None);
    // Inside the fence but within 5 m of its edge.
    assert_eq!(
        airspace.blocked(c(97.0, 0.0)),
        Some(Blocked::OutsideGeofence)
    );
    assert_eq!(
        airspace.blocked(c(200.0, 0.0)),
        Some(Blocked::OutsideGeofence)
    );
    let paths = airspace.paths(&[c(0.0, 0.0), c(15.0, 15.0)]);
    assert_eq!(paths.length_m(0, 1), None);
    assert_eq!(paths.length_m(1, 1), None);
    assert_eq!(paths.length_m(0, 0), Some(0.0));
}

#[test]
fn a_concave_geofence_is_followed_inside() {
    // An L-shaped fence: from the top arm to the right arm the path turns at the inner corner.
    let l = Polygon::new(
        LineString::from(vec![
            (0.0, 0.0),
            (200.0, 0.0),
            (200.0, 50.0),
            (50.0, 50.0),
            (50.0, 200.0),
            (0.0, 200.0),
            (0.0, 0.0),
        ]),
        vec![],
    );
    let fence = MultiPolygon(vec![l]);
    let airspace = Airspace::new(&[], Some(&fence), opts(5.0)).unwrap();
    let (a, b) = (c(25.0, 180.0), c(180.0, 25.0));
    let paths = airspace.paths(&[a, b]);
    let via = paths.via(0, 1).unwrap();
    assert_eq!(via.len(), 1, "{via:?}");
    // The inner corner (50, 50) shrunk by 5.5 m: (44.5, 44.5).
    assert!((via[0].x - 44.5).abs() < 1e-6 && (via[0].y - 44.5).abs() < 1e-6);
    check_path(&airspace, a, via, b, paths.length_m(0, 1).unwrap());
}

#[test]
fn overlapping_zones_merge_and_lines_are_buffered() {
    let line = Geometry::LineString(LineString::from(vec![(50.0, -100.0), (50.0, 100.0)]));
    let airspace = Airspace::new(
        &[
            rect(0.0, 0.0, 30.0, 30.0),
            rect(20.0, 20.0, 40.0, 40.0),
            line,
        ],
        None,
        opts(3.0),
    )
    .unwrap();
    assert_eq!(
        airspace.blocked(c(50.0, 90.0)),
        Some(Blocked::NoFly { zone: 2 })
    );
    assert_eq!(
        airspace.blocked(c(52.9, 0.0)),
        Some(Blocked::NoFly { zone: 2 })
    );
    assert_eq!(airspace.blocked(c(53.1, 0.0)), None);
    let (a, b) = (c(0.0, 60.0), c(100.0, 60.0));
    let paths = airspace.paths(&[a, b]);
    let via = paths.via(0, 1).unwrap();
    assert!(!via.is_empty());
    check_path(&airspace, a, via, b, paths.length_m(0, 1).unwrap());
    // The corner inside the merged zones is no turn point.
    assert!(
        airspace
            .turn_points()
            .iter()
            .all(|t| airspace.blocked(*t).is_none())
    );
}

#[test]
fn hostile_inputs_are_errors() {
    let e = Airspace::new(&[], None, opts(f64::NAN)).unwrap_err();
    assert!(e.to_string().contains("buffer"), "{e}");
    let e = Airspace::new(&[], None, opts(-1.0)).unwrap_err();
    assert!(e.to_string().contains("buffer"), "{e}");
    let bad = rect(0.0, 0.0, f64::INFINITY, 1.0);
    let e = Airspace::new(&[rect(0.0, 0.0, 1.0, 1.0), bad], None, opts(1.0)).unwrap_err();
    assert_eq!(
        e,
        AirspaceError::InvalidZone {
            zone: 1,
            reason: "a coordinate is not a finite number".into()
        }
    );
    let line = Geometry::LineString(LineString::from(vec![(0.0, 0.0), (1.0, 1.0)]));
    let e = Airspace::new(&[line], None, opts(0.0)).unwrap_err();
    assert!(e.to_string().contains("no-fly zone 0"), "{e}");
    let tiny = MultiPolygon(vec![
        Rect::new(coord! {x: 0.0, y: 0.0}, coord! {x: 4.0, y: 4.0}).to_polygon(),
    ]);
    let e = Airspace::new(&[], Some(&tiny), opts(5.0)).unwrap_err();
    assert!(e.to_string().contains("geofence"), "{e}");
}

#[test]
fn snapped_turn_points_are_used_and_stay_free() {
    let mut airspace = Airspace::new(&[rect(40.0, -10.0, 60.0, 10.0)], None, opts(5.0)).unwrap();
    airspace.map_turn_points(|t| c((t.x * 100.0).round() / 100.0, (t.y * 100.0).round() / 100.0));
    let (a, b) = (c(0.0, 0.0), c(100.0, 0.0));
    let paths = airspace.paths(&[a, b]);
    let via = paths.via(0, 1).unwrap();
    for v in via {
        assert!(airspace.turn_points().contains(v));
    }
    check_path(&airspace, a, via, b, paths.length_m(0, 1).unwrap());
}

/// A random convex-ish polygon (a star of `k` vertices around a centre).
fn star(cx: f64, cy: f64, radii: &[f64], phase: f64) -> Geometry<f64> {
    let k = radii.len();
    let mut ring: Vec<(f64, f64)> = radii
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let a = phase + std::f64::consts::TAU * i as f64 / k as f64;
            (cx + r * a.cos(), cy + r * a.sin())
        })
        .collect();
    ring.push(ring[0]);
    Geometry::Polygon(Polygon::new(LineString::from(ring), vec![]))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn paths_avoid_zones_and_are_never_shorter_than_straight(
        zones in proptest::collection::vec(
            (-300.0f64..300.0, -300.0f64..300.0, proptest::collection::vec(5.0f64..40.0, 3..8), 0.0f64..6.3),
            0..8,
        ),
        points in proptest::collection::vec((-400.0f64..400.0, -400.0f64..400.0), 2..8),
        buffer in 0.0f64..8.0,
    ) {
        let geoms: Vec<Geometry<f64>> = zones
            .iter()
            .map(|(x, y, radii, phase)| star(*x, *y, radii, *phase))
            .collect();
        let airspace = Airspace::new(&geoms, None, opts(buffer)).unwrap();
        let pts: Vec<Coord<f64>> = points.iter().map(|&(x, y)| c(x, y)).collect();
        let paths = airspace.paths(&pts);
        for i in 0..pts.len() {
            for j in 0..pts.len() {
                let free = airspace.blocked(pts[i]).is_none() && airspace.blocked(pts[j]).is_none();
                let Some(len) = paths.length_m(i, j) else {
                    prop_assert!(!free || i != j);
                    continue;
                };
                prop_assert!(free);
                let via = paths.via(i, j).unwrap();
                check_path(&airspace, pts[i], via, pts[j], len);
                let straight = dist(pts[i], pts[j]);
                prop_assert!(len >= straight * (1.0 - 1e-12));
                if airspace.segment_clear(pts[i], pts[j]) {
                    prop_assert!(via.is_empty());
                    prop_assert_eq!(len, straight);
                }
                // Every path point is outside every zone itself (unbuffered).
                for v in via {
                    for g in &geoms {
                        prop_assert!(!g.intersects(&geo::Point(*v)));
                    }
                }
            }
        }
    }
}
