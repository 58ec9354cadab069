//! Small per-cell CSV files users hand in (`cell_id,<numbers>...` with a header line): scores
//! for `plan --scores`, class probabilities for `score --probabilities`; and the reader of a
//! small header-line table ([`read_table`]) they share with a campaign's wind file.

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

/// The text of the regular file `path`: a pipe, FIFO, device or stdin (`-`) is refused, as
/// are bytes that are not UTF-8 (the error names the file and line).
pub fn read_text(path: &Path) -> Result<String> {
    require_regular_file(
        path,
        "not a regular file: give the data as a file (pipes, FIFOs and devices are not read)",
    )?;
    let bytes = std::fs::read(path).map_err(|e| AppError::io(path, e))?;
    match String::from_utf8(bytes) {
        Ok(t) => Ok(t),
        Err(e) => {
            let bytes = e.as_bytes();
            let valid = e.utf8_error().valid_up_to();
            let line = bytes[..valid].iter().filter(|&&b| b == b'\n').count() + 1;
            Err(AppError::Invalid(format!(
                "{}:{line}: not valid UTF-8",
                path.display()
            )))
        }
    }
}

/// Refuses `path` unless it is a regular file: stdin (`-`) with
/// [`gleaner_ingest::STDIN_NOT_READ`], a pipe, FIFO or device with `refusal` (a file that is
/// read twice, or whose opening would block, must be a regular one).
pub fn require_regular_file(path: &Path, refusal: &str) -> Result<()> {
    if gleaner_ingest::is_stdin(path) {
        return Err(AppError::io(path, gleaner_ingest::STDIN_NOT_READ));
    }
    let meta = std::fs::metadata(path).map_err(|e| AppError::io(path, e))?;
    if !meta.is_file() {
        return Err(AppError::io(path, refusal));
    }
    Ok(())
}

/// A small CSV file with a header line: the header's column names and the data rows.
pub struct Table {
    /// The header's names, trimmed, as written.
    pub header: Vec<String>,
    /// Per data row: its 1-based line (the header is line 1) and its trimmed fields, as many
    /// as the header's.
    pub rows: Vec<(usize, Vec<String>)>,
}

/// Reads a small comma-separated file with a header line (a regular file only: see
/// [`read_text`]). Blank lines are skipped; a UTF-8 BOM and CRLF are accepted.
///
/// # Errors
/// [`AppError::Invalid`] naming the file and line: an empty file (the message ends with
/// `expected`, e.g. the header the caller wants), a row with another number of fields than
/// the header; bytes that are not UTF-8. [`AppError::Io`] when the file cannot be read.
pub fn read_table(path: &Path, expected: &str) -> Result<Table> {
    let text = read_text(path)?;
    let mut lines = text.trim_start_matches('\u{feff}').lines().enumerate();
    let header: Vec<String> = lines
        .next()
        .filter(|(_, h)| !h.trim().is_empty())
        .map(|(_, h)| h.split(',').map(|c| c.trim().to_string()).collect())
        .ok_or_else(|| {
            AppError::Invalid(format!(
                "{}: empty file: expected a header line{expected}",
                path.display()
            ))
        })?;
    let mut rows = Vec::new();
    for (k, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<String> = line.split(',').map(|f| f.trim().to_string()).collect();
        if fields.len() != header.len() {
            return Err(AppError::Invalid(format!(
                "{}:{}: {} fields, but the header has {}",
                path.display(),
                k + 1,
                fields.len(),
                header.len()
            )));
        }
        rows.push((k + 1, fields));
    }
    Ok(Table { header, rows })
}

/// Reads the file; a field that is not a finite number is an error naming file, line and
/// column (from the header), as is a row with another number of fields than the header, a
/// header naming a column twice and bytes that are not UTF-8. Only regular files are read (a
/// FIFO would block). Blank lines are skipped; a UTF-8 BOM and CRLF are accepted.
pub fn read(path: &Path) -> Result<Vec<CellRow>> {
    let Table {
        header,
        rows: table,
    } = read_table(path, "")?;
    let bad =
        |line: usize, what: String| AppError::Invalid(format!("{}:{line}: {what}", path.display()));
    for (k, name) in header.iter().enumerate() {
        if let Some(first) = header[..k]
            .iter()
            .position(|h| h.eq_ignore_ascii_case(name))
        {
            return Err(bad(
                1,
                format!(
                    "column {}: {:?} repeated (first as column {})",
                    k + 1,
                    gleaner_ingest::shorten(name),
                    first + 1
                ),
            ));
        }
    }
    let mut rows = Vec::new();
    for (line, fields) in table {
        let values = fields[1..]
            .iter()
            .enumerate()
            .map(|(c, v)| {
                let column = header.get(c + 1).map_or("?", String::as_str);
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        bad(
                            line,
                            format!(
                                "column `{}`: not a finite number: {}",
                                gleaner_ingest::shorten(column),
                                gleaner_ingest::quoted(v)
                            ),
                        )
                    })
            })
            .collect::<Result<Vec<f64>>>()?;
        rows.push(CellRow {
            line,
            cell: fields[0].clone(),
            values,
        });
    }
    Ok(rows)
}
