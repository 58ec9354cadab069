//! Small per-cell CSV files users hand in (`cell_id,<numbers>...` with a header line): scores
//! for `plan --scores`, class probabilities for `score --probabilities`.

use std::path::Path;

use crate::error::{AppError, Result};

/// One data row: its 1-based line, the cell id, and the numbers after it.
pub struct CellRow {
    /// 1-based line in the file (the header is line 1).
    pub line: usize,
    /// The cell id as written.
    pub cell: String,
    /// The remaining fields as finite numbers.
    pub values: Vec<f64>,
}

/// Reads the file; a field that is not a finite number is an error naming file, line and
/// column (from the header). Blank lines are skipped; a UTF-8 BOM and CRLF are accepted.
pub fn read(path: &Path) -> Result<Vec<CellRow>> {
    let text = std::fs::read_to_string(path).map_err(|e| AppError::io(path, e))?;
    let mut lines = text.trim_start_matches('\u{feff}').lines().enumerate();
    let header: Vec<String> = lines
        .next()
        .map(|(_, h)| h.split(',').map(|c| c.trim().to_string()).collect())
        .ok_or_else(|| {
            AppError::Invalid(format!(
                "{}: empty file: expected a header line",
                path.display()
            ))
        })?;
    let mut rows = Vec::new();
    for (k, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let mut fields = line.split(',').map(str::trim);
        let cell = fields.next().unwrap_or_default().to_string();
        let values = fields
            .enumerate()
            .map(|(c, v)| {
                let column = header.get(c + 1).map_or("?", String::as_str);
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        AppError::Invalid(format!(
                            "{}:{}: column `{column}`: not a finite number: {v:?}",
                            path.display(),
                            k + 1
                        ))
                    })
            })
            .collect::<Result<Vec<f64>>>()?;
        rows.push(CellRow {
            line: k + 1,
            cell,
            values,
        });
    }
    Ok(rows)
}
