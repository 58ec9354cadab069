//! Parsers for the classic (Tsiligirides / Chao) and OPLib (TSPLIB-derived) formats.

use gleaner_orienteering::Problem;

use crate::error::{FormatError, parse_err};
use crate::instance::{DistanceRule, OpFormat, OpInstance};

/// Most nodes an instance may have: the generic problem stores a dense n x n cost matrix
/// (10,000 nodes: 800 MB).
pub const MAX_NODES: usize = 10_000;

/// `return Err(parse_err(file, line, field, format!(message...)))`.
macro_rules! fail {
    ($file:expr, $line:expr, $field:expr, $($message:tt)+) => {
        return Err(parse_err($file, $line, $field, format!($($message)+)))
    };
}

fn number(file: &str, line: usize, field: &str, tok: &str) -> Result<f64, FormatError> {
    let v: f64 = tok
        .parse()
        .map_err(|_| parse_err(file, line, field, format!("`{tok}` is not a number")))?;
    if !v.is_finite() {
        fail!(file, line, field, "`{tok}` is not finite");
    }
    Ok(v)
}

#[allow(clippy::too_many_arguments)] // private helper shared by the two parsers
fn build_problem(
    name: &str,
    rule: DistanceRule,
    coords: &[[f64; 2]],
    explicit: Option<&Vec<f64>>,
    scores: &[f64],
    budget: f64,
    start: usize,
    end: usize,
    vehicles: usize,
) -> Result<Problem, FormatError> {
    let n = scores.len();
    let cost = match explicit {
        Some(m) => m.clone(),
        None => {
            let mut m = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    m[i * n + j] = rule.distance(coords[i], coords[j]);
                }
            }
            m
        }
    };
    let wrap = |source| FormatError::Problem {
        file: name.to_string(),
        source,
    };
    Problem::new(cost, scores.to_vec(), budget)
        .and_then(|p| p.with_endpoints(start, end))
        .and_then(|p| p.with_vehicles(vehicles))
        .map_err(wrap)
}

/// Parses a classic instance (Tsiligirides 1-3, Chao 64/66; `OP_format.txt`): a first line
/// `Tmax P` (budget per path, number of paths), then one line `x y S` per point. Point 1 is
/// the start, point 2 the end; distances are float Euclidean. `name` names the instance in
/// errors and in the result; `set` is its set (directory) name.
pub fn parse_classic(name: &str, set: &str, text: &str) -> Result<OpInstance, FormatError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let (hl, header) = lines
        .next()
        .ok_or_else(|| parse_err(name, 1, "header", "empty file"))?;
    let toks: Vec<&str> = header.split_whitespace().collect();
    if toks.len() < 2 {
        fail!(name, hl, "header", "expected `Tmax P`, got `{header}`");
    }
    let budget = number(name, hl, "Tmax", toks[0])?;
    let paths = number(name, hl, "P", toks[1])?;
    // One path per point at most (more could never be used); also keeps hostile values from
    // sizing allocations.
    let points = text.lines().filter(|l| !l.trim().is_empty()).count() - 1;
    if paths > points.max(1) as f64 {
        fail!(name, hl, "P", "`{}` paths for {points} points", toks[1]);
    }
    if paths < 1.0 || paths.fract() != 0.0 {
        fail!(name, hl, "P", "`{}` is not a positive integer", toks[1]);
    }
    let mut coords = Vec::new();
    let mut scores = Vec::new();
    for (ln, line) in lines {
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.len() < 3 {
            fail!(name, ln, "point", "expected `x y S`, got `{line}`");
        }
        let x = number(name, ln, "x", t[0])?;
        let y = number(name, ln, "y", t[1])?;
        let s = number(name, ln, "score", t[2])?;
        coords.push([x, y]);
        scores.push(s);
    }
    if coords.len() > MAX_NODES {
        fail!(
            name,
            0,
            "points",
            "{} points, more than the {MAX_NODES} supported",
            coords.len()
        );
    }
    if coords.len() < 2 {
        fail!(
            name,
            0,
            "points",
            "need at least 2 points, got {}",
            coords.len()
        );
    }
    let problem = build_problem(
        name,
        DistanceRule::Euclidean,
        &coords,
        None,
        &scores,
        budget,
        0,
        1,
        paths as usize,
    )?;
    Ok(OpInstance {
        name: name.to_string(),
        set: set.to_string(),
        format: OpFormat::Classic,
        n: coords.len(),
        budget,
        rule: DistanceRule::Euclidean,
        coords,
        explicit: None,
        scores,
        start: 0,
        end: 1,
        problem,
        target: None,
    })
}

/// Parses an OPLib instance (TSPLIB keywords plus `COST_LIMIT` and `NODE_SCORE_SECTION`;
/// `FORMAT.md`). The tour is closed at the first depot of `DEPOT_SECTION` (node 1 when
/// absent). Supported `EDGE_WEIGHT_TYPE`s: EUC_2D, CEIL_2D, ATT, GEO, EXPLICIT (FULL_MATRIX,
/// UPPER_ROW, LOWER_ROW, UPPER_DIAG_ROW, LOWER_DIAG_ROW). `set` is the generation (`gen1`).
pub fn parse_oplib(name: &str, set: &str, text: &str) -> Result<OpInstance, FormatError> {
    let lines: Vec<&str> = text.lines().collect();
    let mut dim: Option<usize> = None;
    let mut budget: Option<f64> = None;
    let mut rule: Option<DistanceRule> = None;
    let mut wformat = String::from("FUNCTION");
    let mut coords: Vec<Option<[f64; 2]>> = Vec::new();
    let mut scores: Vec<Option<f64>> = Vec::new();
    let mut explicit: Option<Vec<f64>> = None;
    let mut depot: Option<usize> = None;
    let mut i = 0;
    let need_dim = |dim: Option<usize>, ln: usize, sec: &str| {
        dim.ok_or_else(|| parse_err(name, ln, sec, "section before DIMENSION"))
    };
    while i < lines.len() {
        let ln = i + 1;
        let line = lines[i].trim();
        i += 1;
        if line.is_empty() {
            continue;
        }
        let (key, value) = match line.split_once(':') {
            Some((k, v)) => (k.trim(), v.trim()),
            None => (line, ""),
        };
        match key {
            // Informational keywords (NAME, COMMENT, TYPE, TSPSOL, DISPLAY_DATA_TYPE...) are
            // skipped below, as is any other `KEY : value` line.
            "DIMENSION" => {
                let d: usize = value
                    .parse()
                    .map_err(|_| parse_err(name, ln, "DIMENSION", format!("`{value}`")))?;
                if d < 1 {
                    return Err(parse_err(name, ln, "DIMENSION", "must be at least 1"));
                }
                // Every node needs a score line, so a larger DIMENSION is a broken (or hostile)
                // file; checked before anything is sized by it.
                if d > lines.len() || d > MAX_NODES {
                    fail!(
                        name,
                        ln,
                        "DIMENSION",
                        "{d} nodes: more than the file's {} lines or the {MAX_NODES} supported",
                        lines.len()
                    );
                }
                dim = Some(d);
                coords = vec![None; d];
                scores = vec![None; d];
            }
            "COST_LIMIT" => budget = Some(number(name, ln, "COST_LIMIT", value)?),
            "EDGE_WEIGHT_TYPE" => {
                rule = Some(match value {
                    "EUC_2D" => DistanceRule::Euc2d,
                    "CEIL_2D" => DistanceRule::Ceil2d,
                    "ATT" => DistanceRule::Att,
                    "GEO" => DistanceRule::Geo,
                    "EXPLICIT" => DistanceRule::Explicit,
                    other => {
                        fail!(name, ln, "EDGE_WEIGHT_TYPE", "unsupported `{other}`");
                    }
                })
            }
            "EDGE_WEIGHT_FORMAT" => wformat = value.to_string(),
            "NODE_COORD_SECTION" | "DISPLAY_DATA_SECTION" | "NODE_SCORE_SECTION" => {
                let d = need_dim(dim, ln, key)?;
                node_section(name, (&lines, &mut i), key, d, (&mut coords, &mut scores))?;
            }
            "EDGE_WEIGHT_SECTION" => {
                let d = need_dim(dim, ln, key)?;
                explicit = Some(edge_weights(name, (&lines, &mut i), ln, &wformat, d)?);
            }
            "DEPOT_SECTION" => depot = depot_section(name, (&lines, &mut i), dim, depot)?,
            "EOF" => break,
            _ if line.contains(':') => {}
            other => fail!(name, ln, "keyword", "unknown `{other}`"),
        }
    }
    let n = dim.ok_or_else(|| parse_err(name, 0, "DIMENSION", "missing"))?;
    let budget = budget.ok_or_else(|| parse_err(name, 0, "COST_LIMIT", "missing"))?;
    let rule = rule.ok_or_else(|| parse_err(name, 0, "EDGE_WEIGHT_TYPE", "missing"))?;
    let scores: Vec<f64> = scores
        .iter()
        .enumerate()
        .map(|(k, s)| {
            s.ok_or_else(|| {
                parse_err(
                    name,
                    0,
                    "NODE_SCORE_SECTION",
                    format!("no score for node {}", k + 1),
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let coords: Vec<[f64; 2]> = if rule == DistanceRule::Explicit {
        if explicit.is_none() {
            return Err(parse_err(
                name,
                0,
                "EDGE_WEIGHT_SECTION",
                "missing for EXPLICIT",
            ));
        }
        Vec::new()
    } else {
        coords
            .iter()
            .enumerate()
            .map(|(k, c)| {
                c.ok_or_else(|| {
                    parse_err(
                        name,
                        0,
                        "NODE_COORD_SECTION",
                        format!("no coordinates for node {}", k + 1),
                    )
                })
            })
            .collect::<Result<_, _>>()?
    };
    let depot = depot.unwrap_or(0);
    let problem = build_problem(
        name,
        rule,
        &coords,
        explicit.as_ref(),
        &scores,
        budget,
        depot,
        depot,
        1,
    )?;
    Ok(OpInstance {
        name: name.to_string(),
        set: set.to_string(),
        format: OpFormat::OpLib,
        n,
        budget,
        rule,
        coords,
        explicit,
        scores,
        start: depot,
        end: depot,
        problem,
        target: None,
    })
}

/// A node section (`NODE_COORD_SECTION`, `DISPLAY_DATA_SECTION`, `NODE_SCORE_SECTION`): `d`
/// lines from line `*i` (0-based) on, into `coords` or `scores` by node id.
fn node_section(
    name: &str,
    (lines, i): (&[&str], &mut usize),
    key: &str,
    d: usize,
    (coords, scores): (&mut [Option<[f64; 2]>], &mut [Option<f64>]),
) -> Result<(), FormatError> {
    for _ in 0..d {
        let Some(raw) = lines.get(*i) else {
            return Err(parse_err(name, *i + 1, key, "unexpected end of file"));
        };
        let row = *i + 1;
        *i += 1;
        let t: Vec<&str> = raw.split_whitespace().collect();
        let width = if key == "NODE_SCORE_SECTION" { 2 } else { 3 };
        if t.len() < width {
            fail!(
                name,
                row,
                key,
                "expected {width} fields, got `{}`",
                raw.trim()
            );
        }
        let id = number(name, row, "node id", t[0])?;
        if id < 1.0 || id > d as f64 || id.fract() != 0.0 {
            fail!(name, row, "node id", "`{}` not in 1..={d}", t[0]);
        }
        let k = id as usize - 1;
        match key {
            "NODE_COORD_SECTION" => {
                coords[k] = Some([number(name, row, "x", t[1])?, number(name, row, "y", t[2])?]);
            }
            "NODE_SCORE_SECTION" => scores[k] = Some(number(name, row, "score", t[1])?),
            _ => {}
        }
    }
    Ok(())
}

/// `EDGE_WEIGHT_SECTION` (opened at line `ln`) in `wformat`, from line `*i` (0-based) on: the
/// symmetric `d` × `d` matrix, row-major, with a zero diagonal.
fn edge_weights(
    name: &str,
    (lines, i): (&[&str], &mut usize),
    ln: usize,
    wformat: &str,
    d: usize,
) -> Result<Vec<f64>, FormatError> {
    let key = "EDGE_WEIGHT_SECTION";
    let count = match wformat {
        "FULL_MATRIX" => d * d,
        "UPPER_ROW" | "LOWER_ROW" => d * (d - 1) / 2,
        "UPPER_DIAG_ROW" | "LOWER_DIAG_ROW" => d * (d + 1) / 2,
        other => {
            fail!(name, ln, "EDGE_WEIGHT_FORMAT", "unsupported `{other}`");
        }
    };
    let mut vals = Vec::with_capacity(count);
    while vals.len() < count {
        let Some(raw) = lines.get(*i) else {
            fail!(name, *i + 1, key, "only {} of {count} weights", vals.len());
        };
        let row = *i + 1;
        *i += 1;
        for tok in raw.split_whitespace() {
            vals.push(number(name, row, "edge weight", tok)?);
        }
    }
    if vals.len() != count {
        fail!(name, *i, key, "{} weights, expected {count}", vals.len());
    }
    let mut m = vec![0.0; d * d];
    let mut it = vals.into_iter();
    let mut set = |a: usize, b: usize, v: f64| {
        m[a * d + b] = v;
        m[b * d + a] = v;
    };
    match wformat {
        "FULL_MATRIX" => {
            for a in 0..d {
                for b in 0..d {
                    let v = it.next().unwrap_or(0.0);
                    if a <= b {
                        set(a, b, v);
                    }
                }
            }
        }
        "UPPER_ROW" => {
            (0..d).for_each(|a| ((a + 1)..d).for_each(|b| set(a, b, it.next().unwrap_or(0.0))))
        }
        "UPPER_DIAG_ROW" => {
            (0..d).for_each(|a| (a..d).for_each(|b| set(a, b, it.next().unwrap_or(0.0))))
        }
        "LOWER_ROW" => {
            (0..d).for_each(|a| (0..a).for_each(|b| set(a, b, it.next().unwrap_or(0.0))))
        }
        _ => (0..d).for_each(|a| (0..=a).for_each(|b| set(a, b, it.next().unwrap_or(0.0)))),
    }
    for a in 0..d {
        m[a * d + a] = 0.0;
    }
    Ok(m)
}

/// `DEPOT_SECTION` from line `*i` (0-based) on, to its `-1`: the first depot (0-based), or
/// `depot` as found before.
fn depot_section(
    name: &str,
    (lines, i): (&[&str], &mut usize),
    dim: Option<usize>,
    mut depot: Option<usize>,
) -> Result<Option<usize>, FormatError> {
    let key = "DEPOT_SECTION";
    while let Some(raw) = lines.get(*i) {
        let row = *i + 1;
        *i += 1;
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        let v = number(name, row, "depot", t)?;
        if v < 0.0 {
            break;
        }
        if depot.is_none() {
            let d = dim.ok_or_else(|| parse_err(name, row, key, "section before DIMENSION"))?;
            if v < 1.0 || v > d as f64 || v.fract() != 0.0 {
                fail!(name, row, "depot", "`{t}` not in 1..={d}");
            }
            depot = Some(v as usize - 1);
        }
    }
    Ok(depot)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parses `text` as OPLib and compares (n, budget, rule, depot, scores) or the error text.
    fn check(text: &str, expected: Result<(usize, f64, DistanceRule, usize, Vec<f64>), &str>) {
        let got = parse_oplib("t", "g", text);
        match (got, expected) {
            (Ok(i), Ok(e)) => assert_eq!((i.n, i.budget, i.rule, i.start, i.scores), e),
            (Err(g), Err(e)) => assert!(g.to_string().contains(e), "{g} does not contain {e}"),
            (g, e) => panic!("got {g:?}, expected {e:?}"),
        }
    }

    const EXPLICIT: &str = "NAME: t\nTYPE: OP\nDIMENSION: 3\nCOST_LIMIT : 7\nEDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: LOWER_DIAG_ROW\nEDGE_WEIGHT_SECTION\n 0 2 0\n 3 4 0\nNODE_SCORE_SECTION\n1 0\n2 5\n3 7\nDEPOT_SECTION\n 2\n-1\nEOF\n";

    #[test]
    fn hostile_sizes_are_errors_before_any_allocation() {
        for dim in ["1000000000000", "18446744073709551615", "10001"] {
            let text = format!(
                "NAME : h\nDIMENSION : {dim}\nCOST_LIMIT : 10\nEDGE_WEIGHT_TYPE : EUC_2D\nEOF\n"
            );
            let e = parse_oplib("h", "x", &text).unwrap_err().to_string();
            assert!(e.contains("DIMENSION"), "{e}");
        }
        let e = parse_oplib(
            "h",
            "x",
            "DIMENSION : 99999999999999999999999\nCOST_LIMIT : 1\nEOF\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("DIMENSION"), "{e}");
        for paths in [
            "1e300",
            "18446744073709551616",
            "4",
            "inf",
            "-1",
            "0",
            "1.5",
        ] {
            let text = format!("10 {paths}\n0 0 0\n1 1 0\n2 2 5\n");
            assert!(parse_classic("c", "x", &text).is_err(), "P = {paths}");
        }
        assert!(parse_classic("c", "x", "10 3\n0 0 0\n1 1 0\n2 2 5\n").is_ok());
        for budget in ["inf", "NaN", "1e400"] {
            let text = format!("{budget} 1\n0 0 0\n1 1 0\n");
            assert!(parse_classic("c", "x", &text).is_err(), "Tmax = {budget}");
        }
    }

    #[test]
    fn oplib() {
        check(
            EXPLICIT,
            Ok((3, 7.0, DistanceRule::Explicit, 1, vec![0.0, 5.0, 7.0])),
        );
        let i = parse_oplib("t", "g", EXPLICIT).unwrap();
        assert_eq!(
            (i.distance(0, 1), i.distance(2, 0), i.distance(1, 2)),
            (2.0, 3.0, 4.0)
        );
        let upper = EXPLICIT
            .replace("LOWER_DIAG_ROW", "UPPER_ROW")
            .replace(" 0 2 0\n 3 4 0\n", "2 3\n4\n");
        let j = parse_oplib("t", "g", &upper).unwrap();
        assert_eq!(
            (j.distance(0, 1), j.distance(2, 0), j.distance(1, 2)),
            (2.0, 3.0, 4.0)
        );
        check(
            &EXPLICIT.replace("3 7\n", "3 x\n"),
            Err("t:13: bad score: `x` is not a number"),
        );
        check(
            &EXPLICIT.replace("EXPLICIT", "XRAY1"),
            Err("unsupported `XRAY1`"),
        );
        check(
            &EXPLICIT.replace("COST_LIMIT : 7\n", ""),
            Err("COST_LIMIT: missing"),
        );
        check(
            &EXPLICIT.replace("3 7\n", ""),
            Err("bad NODE_SCORE_SECTION: expected 2 fields, got `DEPOT_SECTION`"),
        );
        let coords = "NAME : c\nDIMENSION : 2\nTSPSOL : 9\nCOST_LIMIT : 10\nEDGE_WEIGHT_TYPE : EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 3 4.4\nNODE_SCORE_SECTION\n1 1\n2 2\nDEPOT_SECTION\n1\n-1\nEOF\n";
        check(
            coords,
            Ok((2, 10.0, DistanceRule::Euc2d, 0, vec![1.0, 2.0])),
        );
    }

    #[test]
    fn classic() {
        let i = parse_classic("c", "s", "10 1\n0 0 0\n1 0 0\n0 2 5\n").unwrap();
        assert_eq!((i.n, i.budget, i.start, i.end), (3, 10.0, 0, 1));
        assert_eq!(i.problem.cost(0, 2), 2.0);
        let e = parse_classic("c", "s", "10 1\n0 0 0\n1 zero 0\n").unwrap_err();
        assert_eq!(e.to_string(), "c:3: bad y: `zero` is not a number");
        let e = parse_classic("c", "s", "10\n").unwrap_err();
        assert!(e.to_string().contains("expected `Tmax P`"));
        // Budget below the direct start -> end distance.
        let e = parse_classic("c", "s", "0.5 1\n0 0 0\n1 0 0\n").unwrap_err();
        assert!(e.to_string().contains("infeasible"));
    }
}
