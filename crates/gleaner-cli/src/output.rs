//! Standard output: JSON or a table, text that survives a closed pipe, and the scoring's
//! warnings on standard error.

use anyhow::{Context, Result};
use gleaner_app as app;

/// Prints the scoring's warnings on standard error.
pub(crate) fn warn(scoring: &app::Scoring) {
    for w in &scoring.warnings {
        eprintln!("warning: {w}");
    }
}

/// Prints `value` as pretty JSON when `json`, else the text `table` renders.
pub(crate) fn emit<T: serde::Serialize>(
    json: bool,
    value: &T,
    what: &str,
    table: impl FnOnce() -> String,
) -> Result<()> {
    if json {
        let mut text = serde_json::to_string_pretty(value).with_context(|| what.to_string())?;
        text.push('\n');
        out(&text)
    } else {
        out(&table())
    }
}

/// Writes `text` to standard output. A reader that closes the pipe early (`gleaner cells
/// --json | head`) has what it wanted: the rest is dropped quietly, not a panic or an error.
pub(crate) fn out(text: &str) -> Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("writing to standard output"),
    }
}

/// [`out`] with a newline.
pub(crate) fn outln(text: &str) -> Result<()> {
    out(&format!("{text}\n"))
}
