//! The peer study's files: its sensor layouts and its published results, and the CSV
//! reading both (and `hubbard`) share.

use std::path::Path;

use crate::EvalError;

/// One sensor layout: positions in metres, depot at the origin.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Its name (`map_1` ..).
    pub name: String,
    /// Sensor labels (CAF ids), in the layout's node order.
    pub labels: Vec<String>,
    /// East/north metres, same order.
    pub positions: Vec<[f64; 2]>,
}

/// One row of the peer's results.
#[derive(Debug, Clone, PartialEq)]
pub struct PeerResult {
    /// Their method (`mysolu`, `baseline_ml`, `baseline_fs`).
    pub method: String,
    /// Layout name.
    pub layout: String,
    /// Energy capacity, J.
    pub capacity_j: f64,
    /// Sensors visited.
    pub n_selected: usize,
    /// Energy used, J.
    pub energy_j: f64,
    /// Sum over unvisited sensors of the squared error, averaged over the test rows (unit²;
    /// infinite when nothing was visited).
    pub mse: f64,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> EvalError + '_ {
    move |source| EvalError::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub(crate) fn bad(path: &Path, line: u64, field: &str, message: impl Into<String>) -> EvalError {
    EvalError::Bad {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message: message.into(),
    }
}

/// A CSV file's header and its rows, each with its 1-based line.
type CsvTable = (Vec<String>, Vec<(u64, Vec<String>)>);

/// Reads a CSV file with a header into (header, rows with their 1-based line).
pub(crate) fn read_csv(path: &Path) -> Result<CsvTable, EvalError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| bad(path, 1, "header", e.to_string()))?
        .iter()
        .map(|h| h.trim_start_matches('\u{feff}').to_string())
        .collect();
    let mut rows = Vec::new();
    for rec in reader.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            bad(path, line, "row", e.to_string())
        })?;
        let line = rec.position().map_or(0, |p| p.line());
        rows.push((line, rec.iter().map(str::to_string).collect()));
    }
    Ok((header, rows))
}

pub(crate) fn column(path: &Path, header: &[String], name: &str) -> Result<usize, EvalError> {
    header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| bad(path, 1, name, "missing column"))
}

pub(crate) fn number(path: &Path, line: u64, field: &str, text: &str) -> Result<f64, EvalError> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| bad(path, line, field, format!("not a number: {:.40}", text)))?;
    if v.is_nan() {
        return Err(bad(path, line, field, "not a number"));
    }
    Ok(v)
}

/// Reads the layouts file. The `Depot` rows must be at (0, 0) (the protocol's tours start
/// there); every other row is a sensor.
pub fn read_layouts(path: &Path) -> Result<Vec<Layout>, EvalError> {
    let (header, rows) = read_csv(path)?;
    let [c_layout, c_label, c_x, c_y] =
        ["layout", "label", "x_m", "y_m"].map(|n| column(path, &header, n));
    let (c_layout, c_label, c_x, c_y) = (c_layout?, c_label?, c_x?, c_y?);
    let mut layouts: Vec<Layout> = Vec::new();
    for (line, row) in rows {
        let (name, label) = (&row[c_layout], &row[c_label]);
        let x = number(path, line, "x_m", &row[c_x])?;
        let y = number(path, line, "y_m", &row[c_y])?;
        if !(x.is_finite() && y.is_finite()) {
            return Err(bad(path, line, "x_m", "not finite"));
        }
        let idx = match layouts.iter().position(|l| &l.name == name) {
            Some(i) => i,
            None => {
                layouts.push(Layout {
                    name: name.clone(),
                    labels: Vec::new(),
                    positions: Vec::new(),
                });
                layouts.len() - 1
            }
        };
        if label == "Depot" {
            if x != 0.0 || y != 0.0 {
                return Err(bad(path, line, "x_m", "the depot must be at (0, 0)"));
            }
            continue;
        }
        let l = &mut layouts[idx];
        if l.labels.contains(label) {
            return Err(bad(path, line, "label", format!("{label} twice in {name}")));
        }
        l.labels.push(label.clone());
        l.positions.push([x, y]);
    }
    if layouts.is_empty() {
        return Err(bad(path, 0, "layout", "no layouts"));
    }
    Ok(layouts)
}

/// Reads the peer's results file.
pub fn read_results(path: &Path) -> Result<Vec<PeerResult>, EvalError> {
    let (header, rows) = read_csv(path)?;
    let c = |n: &str| column(path, &header, n);
    let (cm, cl, cc, cn, ce, cr) = (
        c("method")?,
        c("map")?,
        c("capacity_J")?,
        c("n_selected")?,
        c("energy_J")?,
        c("mse_sum_over_unvisited")?,
    );
    let mut out = Vec::new();
    for (line, row) in rows {
        let n = number(path, line, "n_selected", &row[cn])?;
        if !(n >= 0.0 && n.fract() == 0.0 && n < 1e6) {
            return Err(bad(path, line, "n_selected", "not a count"));
        }
        out.push(PeerResult {
            method: row[cm].clone(),
            layout: row[cl].clone(),
            capacity_j: number(path, line, "capacity_J", &row[cc])?,
            n_selected: n as usize,
            energy_j: number(path, line, "energy_J", &row[ce])?,
            mse: number(path, line, "mse_sum_over_unvisited", &row[cr])?,
        });
    }
    Ok(out)
}
