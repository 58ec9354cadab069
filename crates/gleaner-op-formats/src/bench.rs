//! Loading benchmark files with their targets, and the benchmark runner.

use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};
use std::time::Instant;

use gleaner_orienteering::{SolveOptions, SolverKind, solve};

use crate::error::{FormatError, parse_err};
use crate::instance::{OpFormat, OpInstance};
use crate::parse::{parse_classic, parse_oplib};

/// The non-blank lines of a small comma-separated file with a header, each with its 1-based
/// line number and its trimmed fields in `columns` (looked up by name; a missing column is an
/// error naming `file`; a missing field is empty).
fn csv_columns<const N: usize>(
    file: &str,
    text: &str,
    columns: [&str; N],
) -> Result<Vec<(usize, [String; N])>, FormatError> {
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines
        .next()
        .map(|(_, l)| l.split(',').map(str::trim).collect())
        .unwrap_or_default();
    let mut at = [0; N];
    for (k, name) in columns.iter().enumerate() {
        at[k] = header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| parse_err(file, 1, name, "missing column"))?;
    }
    Ok(lines
        .filter(|(_, line)| !line.trim().is_empty())
        .map(|(i, line)| {
            let f: Vec<&str> = line.split(',').collect();
            let field = |c: usize| f.get(c).map(|s| s.trim().to_string()).unwrap_or_default();
            (i + 1, at.map(field))
        })
        .collect())
}

/// `tok` as a number, or an error naming `file`, `line` and `field`.
fn number(file: &str, line: usize, field: &str, tok: &str) -> Result<f64, FormatError> {
    tok.parse::<f64>()
        .map_err(|_| parse_err(file, line, field, format!("`{tok}`")))
}

/// Target scores of the classic sets, from `targets.csv` (`set,n,budget,...,target`).
/// Returns `(set, budget, target)` triples.
pub fn parse_classic_targets(text: &str) -> Result<Vec<(String, f64, f64)>, FormatError> {
    const FILE: &str = "targets.csv";
    csv_columns(FILE, text, ["set", "budget", "target"])?
        .into_iter()
        .map(|(line, [set, budget, target])| {
            Ok((
                set,
                number(FILE, line, "budget", &budget)?,
                number(FILE, line, "target", &target)?,
            ))
        })
        .collect()
}

/// Best known scores of OPLib, from `ea4op_best.csv` (`instance,...,ea4op_score,...`).
/// Returns `(instance, score)` pairs.
pub fn parse_oplib_best(text: &str) -> Result<Vec<(String, f64)>, FormatError> {
    const FILE: &str = "ea4op_best.csv";
    csv_columns(FILE, text, ["instance", "ea4op_score"])?
        .into_iter()
        .map(|(line, [instance, score])| Ok((instance, number(FILE, line, "ea4op_score", &score)?)))
        .collect()
}

fn read(path: &Path) -> Result<String, FormatError> {
    std::fs::read_to_string(path).map_err(|source| FormatError::Io {
        file: path.to_path_buf(),
        source,
    })
}

/// Finds `file` in `dir` or its ancestors.
fn find_up(dir: &Path, file: &str) -> Option<PathBuf> {
    dir.ancestors().map(|d| d.join(file)).find(|p| p.is_file())
}

/// Reads one benchmark file: `.oplib` files as OPLib, anything else as the classic format.
/// The set name is the parent directory's name. The target is looked up by instance name in
/// `ea4op_best.csv` (OPLib) or by set and budget in `targets.csv` (classic), searched in the
/// file's directory and its ancestors; a missing table leaves `target` empty.
pub fn load_instance(path: &Path) -> Result<OpInstance, FormatError> {
    let text = read(path)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = path.parent().unwrap_or(Path::new("."));
    let set = dir
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let oplib = path.extension().is_some_and(|e| e == "oplib");
    let mut inst = if oplib {
        parse_oplib(&name, &set, &text)?
    } else {
        parse_classic(&name, &set, &text)?
    };
    match inst.format {
        OpFormat::OpLib => {
            if let Some(t) = find_up(dir, "ea4op_best.csv") {
                let best = parse_oplib_best(&read(&t)?)?;
                inst.target = best.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
            }
        }
        OpFormat::Classic => {
            if let Some(t) = find_up(dir, "targets.csv") {
                let targets = parse_classic_targets(&read(&t)?)?;
                inst.target = targets
                    .iter()
                    .find(|(s, b, _)| *s == set && (b - inst.budget).abs() < 1e-6)
                    .map(|(_, _, t)| *t);
            }
        }
    }
    Ok(inst)
}

/// The benchmark files `path` names: the file itself, or every instance under a directory
/// ([`find_instances`]); with `max_n`, only instances of at most that many nodes.
pub fn benchmark_files(path: &Path, max_n: Option<usize>) -> Result<Vec<PathBuf>, FormatError> {
    let files = if path.is_dir() {
        find_instances(path)?
    } else if path.exists() {
        vec![path.to_path_buf()]
    } else {
        return Err(FormatError::NotFound {
            file: path.to_path_buf(),
        });
    };
    let Some(max) = max_n else { return Ok(files) };
    let mut kept = Vec::new();
    for f in files {
        if load_instance(&f)?.n <= max {
            kept.push(f);
        }
    }
    Ok(kept)
}

/// All benchmark instance files under `dir` (recursively, sorted): `*.oplib` files and the
/// classic `*.txt` files (except `OP_format.txt`).
pub fn find_instances(dir: &Path) -> Result<Vec<PathBuf>, FormatError> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|source| FormatError::Io {
            file: d.clone(),
            source,
        })?;
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "oplib")
                || (p.extension().is_some_and(|x| x == "txt")
                    && p.file_name().is_some_and(|f| f != "OP_format.txt"))
            {
                out.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// One benchmark result.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchRow {
    /// Instance name (file stem).
    pub instance: String,
    /// Set (directory) name.
    pub set: String,
    /// Number of nodes.
    pub n: usize,
    /// Budget (distance unit of the instance).
    pub budget: f64,
    /// Target / best-known score, when known.
    pub target: Option<f64>,
    /// Score found, re-checked with the instance's own distance rule (0 when the routes fail
    /// that re-check).
    pub ours: f64,
    /// `(target - ours) / target · 100` (negative: better than the target).
    pub gap_pct: Option<f64>,
    /// Solve time (s).
    pub seconds: f64,
    /// The routes passed re-validation with the instance's own distance rule.
    pub feasible: bool,
    /// The solver's name (`greedy`, `default`, `exact`).
    pub solver: &'static str,
    /// The solver's routes, one per vehicle, each from the start node to the end node, with
    /// node ids as numbered in the instance file (1-based; see [`OpInstance::node_id`]).
    /// Empty when the solver failed.
    pub routes: Vec<Vec<usize>>,
}

/// Aggregate over [`BenchRow`]s.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchSummary {
    /// Number of instances.
    pub count: usize,
    /// Instances with a known target.
    pub with_target: usize,
    /// Instances reaching or beating the target.
    pub matched: usize,
    /// Instances strictly beating the target.
    pub beat: usize,
    /// Mean gap over instances with a target (%).
    pub mean_gap_pct: f64,
    /// Worst (largest) gap (%).
    pub worst_gap_pct: f64,
    /// Instances whose solution failed re-validation.
    pub infeasible: usize,
    /// Total solve time (s).
    pub total_seconds: f64,
}

/// Solves every file in `paths` with `solver` and `options`, re-validates each route with
/// the instance's own distance rule, and calls `progress(done, total, row)` after each.
/// Files that cannot be read or parsed stop the run with their error.
pub fn run_benchmark(
    paths: &[PathBuf],
    solver: SolverKind,
    options: &SolveOptions,
    progress: &mut dyn FnMut(usize, usize, &BenchRow),
) -> Result<Vec<BenchRow>, FormatError> {
    let mut rows = Vec::with_capacity(paths.len());
    for (k, path) in paths.iter().enumerate() {
        let inst = load_instance(path)?;
        let row = run_instance(&inst, solver, options);
        progress(k + 1, paths.len(), &row);
        rows.push(row);
    }
    Ok(rows)
}

/// Solves one instance and builds its row (see [`run_benchmark`]).
pub fn run_instance(inst: &OpInstance, solver: SolverKind, options: &SolveOptions) -> BenchRow {
    let t0 = Instant::now();
    let result = solve(&inst.problem, solver, options);
    let seconds = t0.elapsed().as_secs_f64();
    let (ours, feasible, routes) = match result {
        Ok(sol) => {
            let ids = sol
                .routes
                .iter()
                .map(|r| r.iter().map(|&v| inst.node_id(v)).collect())
                .collect();
            match inst.score_routes(&sol.routes) {
                Ok(score) => (score, true, ids),
                Err(_) => (0.0, false, ids),
            }
        }
        Err(_) => (0.0, false, Vec::new()),
    };
    let gap_pct = inst
        .target
        .filter(|t| *t > 0.0)
        .map(|t| (t - ours) / t * 100.0);
    BenchRow {
        instance: inst.name.clone(),
        set: inst.set.clone(),
        n: inst.n,
        budget: inst.budget,
        target: inst.target,
        ours,
        gap_pct,
        seconds,
        feasible,
        solver: solver.name(),
        routes,
    }
}

/// Summarises rows (a score counts as matching when within 1e-6 of the target).
pub fn summarize(rows: &[BenchRow]) -> BenchSummary {
    let gaps: Vec<f64> = rows.iter().filter_map(|r| r.gap_pct).collect();
    let with: Vec<&BenchRow> = rows.iter().filter(|r| r.target.is_some()).collect();
    BenchSummary {
        count: rows.len(),
        with_target: with.len(),
        matched: with
            .iter()
            .filter(|r| r.target.is_some_and(|t| r.ours >= t - 1e-6))
            .count(),
        beat: with
            .iter()
            .filter(|r| r.target.is_some_and(|t| r.ours > t + 1e-6))
            .count(),
        mean_gap_pct: if gaps.is_empty() {
            0.0
        } else {
            gaps.iter().sum::<f64>() / gaps.len() as f64
        },
        worst_gap_pct: gaps.iter().copied().fold(0.0, f64::max),
        infeasible: rows.iter().filter(|r| !r.feasible).count(),
        total_seconds: rows.iter().map(|r| r.seconds).sum(),
    }
}

/// How a row's values are written: for reading in an aligned table, or exactly for CSV.
#[derive(Clone, Copy, PartialEq)]
enum Style {
    Table,
    Csv,
}

/// A row's nine columns, in the order `instance, set, n, budget, target, ours, gap, seconds,
/// feasible`; the table rounds (target to 0 digits, gap to 2, seconds to 3) and shows a
/// missing value as `-`, the CSV keeps 4 digits and leaves it empty.
fn columns(r: &BenchRow, style: Style) -> [String; 9] {
    let table = style == Style::Table;
    let missing = || {
        if table {
            "-".to_string()
        } else {
            String::new()
        }
    };
    [
        r.instance.clone(),
        r.set.clone(),
        r.n.to_string(),
        r.budget.to_string(),
        r.target.map_or_else(missing, |t| {
            if table {
                format!("{t:.0}")
            } else {
                t.to_string()
            }
        }),
        r.ours.to_string(),
        r.gap_pct
            .map_or_else(missing, |g| format!("{:.*}", if table { 2 } else { 4 }, g)),
        format!("{:.*}", if table { 3 } else { 4 }, r.seconds),
        match (table, r.feasible) {
            (true, true) => "yes".to_string(),
            (true, false) => "NO".to_string(),
            (false, f) => f.to_string(),
        },
    ]
}

/// The rows as an aligned text table followed by the summary line.
pub fn format_table(rows: &[BenchRow]) -> String {
    let header = [
        "instance", "set", "n", "budget", "target", "ours", "gap_%", "secs", "feasible",
    ]
    .map(String::from);
    let body: Vec<[String; 9]> = rows.iter().map(|r| columns(r, Style::Table)).collect();
    // The first two columns are left-aligned at least 8 and 3 wide, the others right-aligned
    // at 6, 10, 10, 10, 8, 8, 8.
    let mut widths = [8, 3, 6, 10, 10, 10, 8, 8, 8];
    for line in &body {
        for k in 0..2 {
            widths[k] = widths[k].max(line[k].len());
        }
    }
    let mut s = String::new();
    for line in std::iter::once(&header).chain(&body) {
        let cells: Vec<String> = line
            .iter()
            .zip(widths)
            .enumerate()
            .map(|(k, (v, w))| {
                if k < 2 {
                    format!("{v:<w$}")
                } else {
                    format!("{v:>w$}")
                }
            })
            .collect();
        let _ = writeln!(s, "{}", cells.join(" "));
    }
    let sm = summarize(rows);
    let _ = writeln!(
        s,
        "{} instances, {} with target: {} matched ({} beat), mean gap {:.3}%, worst gap {:.3}%, {} infeasible, {:.1} s total",
        sm.count,
        sm.with_target,
        sm.matched,
        sm.beat,
        sm.mean_gap_pct,
        sm.worst_gap_pct,
        sm.infeasible,
        sm.total_seconds
    );
    s
}

/// The rows as CSV with a header line (`instance,set,n,budget,target,ours,gap_pct,seconds,feasible`).
pub fn format_csv(rows: &[BenchRow]) -> String {
    let mut s = String::from("instance,set,n,budget,target,ours,gap_pct,seconds,feasible\n");
    for r in rows {
        let _ = writeln!(s, "{}", columns(r, Style::Csv).join(","));
    }
    s
}

/// Writes every row's routes, one line per instance, so that anyone can re-check a claimed
/// score with their own tools:
///
/// `instance<TAB>solver<TAB>score<TAB>route`
///
/// where `route` is the node ids, as numbered in the instance file (1-based), separated by
/// single spaces, from the start node to the end node (classic: `1 ... 2`; OPLib: a closed
/// tour `1 ... 1` from the depot). With several vehicles each further route follows in its
/// own TAB-separated column. `score` is the score the runner re-checked (0 when the routes
/// failed re-validation, see [`BenchRow::feasible`]), printed exactly (shortest round-trip
/// form). Tabs and line breaks in instance names are written as spaces. [`parse_routes`]
/// reads the lines back.
///
/// # Errors
/// The writer's IO errors.
pub fn write_routes(rows: &[BenchRow], out: &mut impl io::Write) -> io::Result<()> {
    for r in rows {
        let name: String = r
            .instance
            .chars()
            .map(|c| {
                if matches!(c, '\t' | '\n' | '\r') {
                    ' '
                } else {
                    c
                }
            })
            .collect();
        write!(out, "{name}\t{}\t{}", r.solver, r.ours)?;
        for route in &r.routes {
            out.write_all(b"\t")?;
            for (k, id) in route.iter().enumerate() {
                if k > 0 {
                    out.write_all(b" ")?;
                }
                write!(out, "{id}")?;
            }
        }
        out.write_all(b"\n")?;
    }
    Ok(())
}

/// One line of a routes file (see [`write_routes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RouteRecord {
    /// Instance name.
    pub instance: String,
    /// Solver name.
    pub solver: String,
    /// Claimed score.
    pub score: f64,
    /// Routes, node ids as numbered in the instance file (convert with
    /// [`OpInstance::route_from_node_ids`], re-check with [`OpInstance::score_routes`]).
    pub routes: Vec<Vec<usize>>,
}

/// Reads a routes file written by [`write_routes`] (blank lines are ignored).
///
/// # Errors
/// [`FormatError::Parse`] naming the line and field (`routes` as the file name).
pub fn parse_routes(text: &str) -> Result<Vec<RouteRecord>, FormatError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let ln = i + 1;
        let f: Vec<&str> = line.split('\t').collect();
        if f.len() < 3 {
            return Err(parse_err(
                "routes",
                ln,
                "line",
                format!("expected `instance<TAB>solver<TAB>score<TAB>route`, got `{line}`"),
            ));
        }
        let score = f[2]
            .trim()
            .parse::<f64>()
            .map_err(|_| parse_err("routes", ln, "score", format!("`{}`", f[2])))?;
        let routes = f[3..]
            .iter()
            .map(|r| {
                r.split_whitespace()
                    .map(|t| {
                        t.parse::<usize>()
                            .map_err(|_| parse_err("routes", ln, "node id", format!("`{t}`")))
                    })
                    .collect::<Result<Vec<usize>, _>>()
            })
            .collect::<Result<Vec<_>, _>>()?;
        out.push(RouteRecord {
            instance: f[0].to_string(),
            solver: f[1].to_string(),
            score,
            routes,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows() -> Vec<BenchRow> {
        let row =
            |instance: &str, set: &str, n, budget, target, ours, gap_pct, seconds, feasible| {
                BenchRow {
                    instance: instance.to_string(),
                    set: set.to_string(),
                    n,
                    budget,
                    target,
                    ours,
                    gap_pct,
                    seconds,
                    feasible,
                    solver: "ils",
                    routes: Vec::new(),
                }
            };
        vec![
            row(
                "tsiligirides_1",
                "tsil",
                32,
                5.0,
                Some(10.0),
                10.0,
                Some(0.0),
                0.01234,
                true,
            ),
            row("x", "oplib-long", 7, 12.5, None, 3.5, None, 1.5, false),
        ]
    }

    /// The table and the CSV of a row with a target and of an infeasible row without one.
    #[test]
    fn table_and_csv_snapshots() {
        assert_eq!(
            format_table(&rows()),
            "\
instance       set             n     budget     target       ours    gap_%     secs feasible
tsiligirides_1 tsil           32          5         10         10     0.00    0.012      yes
x              oplib-long      7       12.5          -        3.5        -    1.500       NO
2 instances, 1 with target: 1 matched (0 beat), mean gap 0.000%, worst gap 0.000%, 1 infeasible, 1.5 s total
"
        );
        assert_eq!(
            format_csv(&rows()),
            "\
instance,set,n,budget,target,ours,gap_pct,seconds,feasible
tsiligirides_1,tsil,32,5,10,10,0.0000,0.0123,true
x,oplib-long,7,12.5,,3.5,,1.5000,false
"
        );
    }
}
