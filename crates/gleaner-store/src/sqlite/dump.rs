//! A text dump of every table, for tests that prove a refused command wrote nothing.

use rusqlite::types::ValueRef;

use super::{Db, SqliteStore};
use crate::Result;

impl SqliteStore {
    /// Every row of every table (schema bookkeeping included), as text: tables by name, rows sorted
    /// by their text, one line per row with each column's value (`NULL`, integers, reals by their
    /// bit pattern, text, blobs as hex). Two dumps are equal exactly when the stored data is.
    pub fn dump(&self) -> Result<String> {
        let tables: Vec<String> = self
            .conn
            .prepare(
                "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'
                 ORDER BY name",
            )
            .db()?
            .query_map([], |r| r.get(0))
            .db()?
            .collect::<rusqlite::Result<_>>()
            .db()?;
        let mut out = String::new();
        for table in tables {
            out.push_str(&format!("[{table}]\n"));
            let quoted = table.replace('"', "\"\"");
            let mut stmt = self
                .conn
                .prepare(&format!("SELECT * FROM \"{quoted}\""))
                .db()?;
            let n = stmt.column_count();
            let mut rows = stmt.query([]).db()?;
            let mut lines = Vec::new();
            while let Some(row) = rows.next().db()? {
                let mut out = String::new();
                for k in 0..n {
                    if k > 0 {
                        out.push('|');
                    }
                    match row.get_ref(k).db()? {
                        ValueRef::Null => out.push_str("NULL"),
                        ValueRef::Integer(i) => out.push_str(&i.to_string()),
                        ValueRef::Real(x) => out.push_str(&format!("{x}#{:x}", x.to_bits())),
                        ValueRef::Text(t) => {
                            out.push_str(&format!("{:?}", String::from_utf8_lossy(t)))
                        }
                        ValueRef::Blob(b) => {
                            out.push_str("x'");
                            for byte in b {
                                out.push_str(&format!("{byte:02x}"));
                            }
                            out.push('\'');
                        }
                    }
                }
                lines.push(out);
            }
            lines.sort();
            for line in lines {
                out.push_str(&line);
                out.push('\n');
            }
        }
        Ok(out)
    }
}
