//! A table as the outputs hold it: named columns of [`Cell`]s, written as CSV or as a JSON array
//! of rows (Parquet: [`crate::table_files`]).

use serde_json::{json, Map, Value};

/// One field of a table.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// An integer: a count, an id or a frame number.
    Int(i64),
    /// A number and the decimals it is written with in CSV.
    Float(f64, usize),
    /// Free text (quoted in CSV when it holds a comma, quote or line break).
    Text(String),
    /// No value (written as an empty CSV field, JSON `null`).
    Empty,
}

impl Cell {
    pub(crate) fn int(v: usize) -> Self {
        Cell::Int(v as i64)
    }
    pub(crate) fn opt(v: Option<f64>, decimals: usize) -> Self {
        v.map_or(Cell::Empty, |v| Cell::Float(v, decimals))
    }
    /// The value as JSON.
    pub fn to_json(&self) -> Value {
        match self {
            Cell::Int(v) => json!(v),
            Cell::Float(v, _) => json!(v),
            Cell::Text(s) => json!(s),
            Cell::Empty => Value::Null,
        }
    }
    /// Appends the cell as CSV to `s`.
    fn push_csv(&self, s: &mut String) {
        use std::fmt::Write;
        match self {
            // Writing to a String cannot fail.
            Cell::Int(v) => {
                let _ = write!(s, "{v}");
            }
            Cell::Float(v, d) => push_fixed(s, *v, *d),
            Cell::Text(t) => s.push_str(&csv_text(t)),
            Cell::Empty => {}
        }
    }
}

/// Powers of ten exact in `f64`, for [`push_fixed`].
const POW10: [f64; 16] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
];

/// Appends `v` with `d` decimals, byte for byte as `format!("{v:.d$}")` writes it (the exact
/// value rounded half to even, a sign on every negative value, `-0.00` included), without the
/// formatting machinery for the common case: `|v|·10^d` below 2^52, rounded as an integer
/// wherever its product in `f64` (off by at most `|v|·10^d·ε`) cannot be on the other side of
/// a half from the exact one. Anything else (a half within that distance, a large or non-finite
/// value, more than 15 decimals) goes to `format!`.
fn push_fixed(s: &mut String, v: f64, d: usize) {
    use std::fmt::Write;
    if v.is_finite() && d < POW10.len() {
        let scaled = v.abs() * POW10[d];
        if scaled < 4.0e15 {
            let whole = scaled.floor();
            // Exact: `scaled` is a multiple of its ulp (at most 1), so is `whole`.
            let frac = scaled - whole;
            if (frac - 0.5).abs() > 2.0 * f64::EPSILON * scaled {
                let n = whole as u64 + u64::from(frac > 0.5);
                if v.is_sign_negative() {
                    s.push('-');
                }
                let unit = 10u64.pow(d as u32);
                let _ = write!(s, "{}", n / unit);
                if d > 0 {
                    let _ = write!(s, ".{:0d$}", n % unit);
                }
                return;
            }
        }
    }
    let _ = write!(s, "{v:.d$}");
}

/// A text cell as CSV. Text a spreadsheet would run as a formula (its first character `=`, `+`,
/// `-`, `@`, a tab or a carriage return: a file name or a unit such as `=HYPERLINK(...)`) is
/// neutralised by a leading `'`, as OWASP recommends; numbers are never text cells, so a
/// negative number stays a number. Then, as RFC 4180 says, text holding a comma, quote or line
/// break (an error message) goes in double quotes, inner quotes doubled.
fn csv_text(s: &str) -> String {
    let formula = s.starts_with(['=', '+', '-', '@', '\t', '\r']);
    let s = if formula {
        std::borrow::Cow::Owned(format!("'{s}"))
    } else {
        std::borrow::Cow::Borrowed(s)
    };
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.into_owned()
    }
}

/// A table: named columns (units in the names) and rows of cells.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column names, units in the names (`time_s`, `x_mm`).
    pub header: Vec<String>,
    /// Rows, each meant to hold one cell per column of [`header`](Self::header) (not checked).
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    pub(crate) fn new(header: &[&str]) -> Self {
        Self {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }
    pub(crate) fn push_column(&mut self, name: &str) {
        self.header.push(name.to_string());
    }
    /// The table as CSV with a header line (free text quoted as RFC 4180 says).
    pub fn to_csv(&self) -> String {
        let mut s = self.header.join(",");
        s.push('\n');
        for r in &self.rows {
            push_csv_row(&mut s, r);
        }
        s
    }
}

/// Appends one CSV line of `cells` (as [`Table::to_csv`] writes it) to `s`.
pub fn push_csv_line(s: &mut String, cells: &[Cell]) {
    push_csv_row(s, cells)
}

fn push_csv_row(s: &mut String, cells: &[Cell]) {
    for (k, c) in cells.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        c.push_csv(s);
    }
    s.push('\n');
}

/// Writes a table as CSV, byte for byte as [`Table::to_csv`] would, from its header and a source
/// of rows (`rows(emit)` calls `emit` for each row in order), without holding the rows: the
/// large tables of a long recording (matches, tracks) go to disk as they are produced.
pub fn write_csv(
    w: &mut dyn std::io::Write,
    header: &[String],
    rows: impl FnOnce(&mut dyn FnMut(Vec<Cell>) -> std::io::Result<()>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut line = header.join(",");
    line.push('\n');
    w.write_all(line.as_bytes())?;
    rows(&mut |cells| {
        line.clear();
        push_csv_row(&mut line, &cells);
        w.write_all(line.as_bytes())
    })
}

impl Table {
    /// The rows as JSON objects keyed by column name.
    pub fn to_json(&self) -> Value {
        Value::Array(
            self.rows
                .iter()
                .map(|r| row_json(&self.header, r))
                .collect(),
        )
    }

    /// Writes [`Table::to_json`] pretty-printed, with a final newline, byte for byte as
    /// `serde_json::to_string_pretty` would, one row at a time: the JSON values of a long
    /// table's cells take several times the memory of the table.
    pub fn write_json(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut rows = JsonRows::new(&self.header);
        for r in &self.rows {
            rows.push(w, r)?;
        }
        rows.finish(w)
    }
}

/// One row as a JSON object keyed by column name.
fn row_json(header: &[String], row: &[Cell]) -> Value {
    let m: Map<String, Value> = header
        .iter()
        .cloned()
        .zip(row.iter().map(Cell::to_json))
        .collect();
    Value::Object(m)
}

/// A JSON array of rows written one at a time, byte for byte as [`Table::write_json`] writes
/// the whole table: for tables whose rows are never all held (a streamed run's `pairs.json`).
pub(crate) struct JsonRows {
    header: Vec<String>,
    rows: usize,
}

impl JsonRows {
    /// An array of objects keyed by these column names.
    pub fn new(header: &[String]) -> Self {
        Self {
            header: header.to_vec(),
            rows: 0,
        }
    }

    /// Writes one row (a cell per column).
    pub fn push(&mut self, w: &mut dyn std::io::Write, row: &[Cell]) -> std::io::Result<()> {
        w.write_all(if self.rows == 0 { b"[\n" } else { b",\n" })?;
        self.rows += 1;
        // One level deeper than alone: every line indented by two spaces (strings hold no
        // line breaks: JSON escapes them).
        let row = serde_json::to_string_pretty(&row_json(&self.header, row))?;
        for (i, line) in row.lines().enumerate() {
            if i > 0 {
                w.write_all(b"\n")?;
            }
            w.write_all(b"  ")?;
            w.write_all(line.as_bytes())?;
        }
        Ok(())
    }

    /// Closes the array (with a final newline).
    pub fn finish(self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        w.write_all(if self.rows == 0 { b"[]\n" } else { b"\n]\n" })
    }
}

#[cfg(test)]
mod csv_tests {
    use super::*;

    #[test]
    fn streamed_csv_equals_the_whole_table() {
        let mut t = Table::new(&["a", "b", "c"]);
        t.rows
            .push(vec![Cell::Int(1), Cell::Float(2.5, 3), Cell::Empty]);
        t.rows.push(vec![
            Cell::Text("x, \"y\"".into()),
            Cell::Int(-4),
            Cell::Float(0.1, 1),
        ]);
        let mut out = Vec::new();
        write_csv(&mut out, &t.header, |emit| {
            t.rows.iter().try_for_each(|r| emit(r.clone()))
        })
        .unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), t.to_csv());
        assert_eq!(t.to_csv(), "a,b,c\n1,2.500,\n\"x, \"\"y\"\"\",-4,0.1\n");
    }

    #[test]
    fn text_a_spreadsheet_would_run_is_neutralised_numbers_never() {
        let mut t = Table::new(&["name", "value"]);
        for text in [
            "=HYPERLINK(\"http://x\")",
            "+1",
            "-2",
            "@SUM(A1)",
            "\tx",
            "\rx",
            "walk",
        ] {
            t.rows
                .push(vec![Cell::Text(text.into()), Cell::Float(-1.5, 1)]);
        }
        t.rows.push(vec![Cell::Int(-3), Cell::Empty]);
        assert_eq!(
            t.to_csv(),
            "name,value\n\"'=HYPERLINK(\"\"http://x\"\")\",-1.5\n'+1,-1.5\n'-2,-1.5\n\
             '@SUM(A1),-1.5\n'\tx,-1.5\n\"'\rx\",-1.5\nwalk,-1.5\n-3,\n"
        );
        // JSON keeps the text as it is.
        assert_eq!(t.to_json()[0]["name"], "=HYPERLINK(\"http://x\")");
    }

    #[test]
    fn streamed_json_equals_the_whole_table_pretty_printed() {
        let whole = |t: &Table| serde_json::to_string_pretty(&t.to_json()).unwrap() + "\n";
        let streamed = |t: &Table| {
            let mut out = Vec::new();
            t.write_json(&mut out).unwrap();
            String::from_utf8(out).unwrap()
        };
        let mut t = Table::new(&["a", "b", "c"]);
        assert_eq!(streamed(&t), whole(&t));
        t.rows
            .push(vec![Cell::Int(1), Cell::Float(2.5, 3), Cell::Empty]);
        t.rows.push(vec![
            Cell::Text("two\nlines, \"quoted\"".into()),
            Cell::Int(-4),
            Cell::Float(0.1, 1),
        ]);
        assert_eq!(streamed(&t), whole(&t));
        assert!(streamed(&t).starts_with("[\n  {\n    \"a\": 1,"));
    }

    fn fixed(v: f64, d: usize) -> String {
        let mut s = String::new();
        push_fixed(&mut s, v, d);
        s
    }

    #[test]
    fn fixed_decimals_are_formats_own_at_halves_signs_and_extremes() {
        let halves = [
            0.5,
            1.5,
            2.5,
            0.125,
            0.375,
            1.005,
            2.675,
            1e15 + 0.5,
            4503599627370495.5,
        ];
        let others = [
            0.0,
            -0.0,
            -0.0001,
            -0.4,
            1e-310,
            3.999e15,
            4.0e15,
            1e300,
            f64::MAX,
        ];
        let odd = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
        ];
        for v in halves.into_iter().chain(others).chain(odd) {
            for v in [v, -v] {
                for d in [0, 1, 2, 3, 6, 15, 16, 20] {
                    assert_eq!(fixed(v, d), format!("{v:.d$}"), "{v:e} with {d} decimals");
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn fixed_decimals_are_formats_own(bits in proptest::num::u64::ANY, d in 0usize..17) {
            let v = f64::from_bits(bits);
            proptest::prop_assert_eq!(fixed(v, d), format!("{v:.d$}"));
        }

        // Values as tables hold them: a few decimals' worth, ties among them.
        #[test]
        fn fixed_decimals_of_table_values_are_formats_own(
            units in -10_000_000i64..10_000_000,
            scale in 0usize..8,
            d in 0usize..7,
        ) {
            let v = units as f64 / POW10[scale];
            proptest::prop_assert_eq!(fixed(v, d), format!("{v:.d$}"));
        }
    }
}
