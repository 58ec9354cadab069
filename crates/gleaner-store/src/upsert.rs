//! The child tables of the cell metadata as both backends upsert them: a table's key columns
//! (a row's identity), then its value columns (what an upsert replaces), in the order the
//! writes bind them. Each backend words its own statement from these lists.

/// A child table of `cell_metadata` and its columns.
pub(crate) struct ChildTable {
    /// The table's name.
    pub(crate) name: &'static str,
    /// The columns that identify a row (the conflict target), bound first.
    pub(crate) keys: &'static [&'static str],
    /// The columns an upsert replaces, bound after the keys.
    pub(crate) values: &'static [&'static str],
}

/// `cell_summaries`: a cell's per-modality series statistics.
pub(crate) const SUMMARIES: ChildTable = ChildTable {
    name: "cell_summaries",
    keys: &["cell", "modality"],
    values: &[
        "count",
        "mean",
        "std",
        "min",
        "max",
        "latest_t",
        "latest_value",
    ],
};

/// `cell_correlations`: a cell's correlation with a neighbour in one modality.
pub(crate) const CORRELATIONS: ChildTable = ChildTable {
    name: "cell_correlations",
    keys: &["cell", "neighbour", "modality"],
    values: &["correlation", "overlap"],
};

/// `cell_anomalies`: a cell's anomaly in one modality at one time.
pub(crate) const ANOMALIES: ChildTable = ChildTable {
    name: "cell_anomalies",
    keys: &["cell", "modality", "t"],
    values: &["anomaly", "flagged"],
};

impl ChildTable {
    /// `INSERT INTO name (keys, values) VALUES (..) ON CONFLICT (keys) DO UPDATE SET value =
    /// excluded.value, ..`, its parameters numbered from 1 after `marker` (`?` for SQLite, `$`
    /// for PostgreSQL).
    pub(crate) fn upsert(&self, marker: char) -> String {
        let columns: Vec<&str> = self.keys.iter().chain(self.values).copied().collect();
        let params: Vec<String> = (1..=columns.len())
            .map(|k| format!("{marker}{k}"))
            .collect();
        format!(
            "INSERT INTO {} ({}) VALUES ({}) ON CONFLICT ({}) DO UPDATE SET {}",
            self.name,
            columns.join(", "),
            params.join(", "),
            self.keys.join(", "),
            self.each_value(" = ", ", "),
        )
    }

    /// Every value column as `value{op}excluded.value`, joined by `sep`.
    pub(crate) fn each_value(&self, op: &str, sep: &str) -> String {
        let terms: Vec<String> = self
            .values
            .iter()
            .map(|v| format!("{v}{op}excluded.{v}"))
            .collect();
        terms.join(sep)
    }
}
