//! Table files: CSV or Parquet (`--tables csv|parquet`, `tables="parquet"` in Python).
//!
//! Every table of a run (pairs, objects, matches, tracks, frames, curves) and a study's tables is written
//! in one of two formats, with the same columns (the same names, units in the names: see
//! [`crate::table`]) and the same rows:
//!
//! - **CSV** (`NAME.csv`): a header line, then one line per row; an empty field is no value.
//! - **Parquet** (`NAME.parquet`): one typed, nullable column per CSV column. Integers are
//!   `INT64`, numbers `DOUBLE` holding the value as the CSV writes it (rounded to the same
//!   decimals, so both formats load to the same numbers), text `BYTE_ARRAY` (UTF-8 string); an
//!   empty CSV field is a null. Snappy-compressed, in row groups of at most [`ROW_GROUP_ROWS`]
//!   rows written as the rows come, so a long recording's matches never sit whole in memory.
//!
//! A column's type is that of its values; a column that is empty throughout its first row group
//! gets the type its name says (text for `status`, `reason`, `path`, `output`, `format`,
//! `message`; integers for counts), else `DOUBLE`.

use crate::outdir::OutDir;
use crate::{Cell, Table};
use parquet::basic::{Compression, LogicalType, Repetition, Type as PhysicalType};
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;
use std::io::Write;
use std::sync::Arc;

/// The file format of a run's tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TableFormat {
    /// Comma-separated text with a header line.
    #[default]
    Csv,
    /// Apache Parquet: typed, compressed columns.
    Parquet,
}

modal_core::choice!(TableFormat, "tables", [
    "csv" => TableFormat::Csv,
    "parquet" => TableFormat::Parquet,
]);

impl TableFormat {
    /// The file name extension (without the dot).
    pub fn extension(self) -> &'static str {
        match self {
            TableFormat::Csv => "csv",
            TableFormat::Parquet => "parquet",
        }
    }

    /// The file name of table `stem`: `matches.csv` or `matches.parquet`.
    pub fn file_name(self, stem: &str) -> String {
        format!("{stem}.{}", self.extension())
    }
}

/// Rows in one Parquet row group: the rows buffered before they are written.
pub const ROW_GROUP_ROWS: usize = 65_536;

/// Writes `table` into `dir` as `{stem}.csv` or `{stem}.parquet`.
pub fn write_table(
    dir: &OutDir,
    format: TableFormat,
    stem: &str,
    table: &Table,
) -> pedo_io::Result<()> {
    match format {
        TableFormat::Csv => dir.write(&format.file_name(stem), table.to_csv().as_bytes()),
        TableFormat::Parquet => dir.write_with(&format.file_name(stem), |w| {
            let mut p = ParquetWriter::new(w, &table.header);
            for row in &table.rows {
                p.push(row)?;
            }
            p.finish()
        }),
    }
}

/// A table file of an output folder written row by row, as CSV or Parquet: the rows are never
/// held (Parquet buffers one row group). The file is complete once [`TableWriter::finish`]
/// returns.
pub(crate) struct TableWriter {
    rel: String,
    sink: TableSink,
}

enum TableSink {
    Csv {
        w: std::io::BufWriter<std::fs::File>,
        line: String,
    },
    Parquet(Box<ParquetWriter<std::io::BufWriter<std::fs::File>>>),
}

impl TableWriter {
    /// Starts `{stem}.csv` or `{stem}.parquet` in `dir` with these columns.
    pub fn create(
        dir: &OutDir,
        format: TableFormat,
        stem: &str,
        header: &[String],
    ) -> pedo_io::Result<Self> {
        let rel = format.file_name(stem);
        let mut w = dir.create_file(&rel)?;
        let sink = match format {
            TableFormat::Csv => {
                let mut line = header.join(",");
                line.push('\n');
                w.write_all(line.as_bytes())
                    .map_err(|e| dir.failed(&rel, e))?;
                TableSink::Csv { w, line }
            }
            TableFormat::Parquet => TableSink::Parquet(Box::new(ParquetWriter::new(w, header))),
        };
        Ok(Self { rel, sink })
    }

    /// Adds one row (a cell per column).
    pub fn push(&mut self, dir: &OutDir, cells: &[Cell]) -> pedo_io::Result<()> {
        let written = match &mut self.sink {
            TableSink::Csv { w, line } => {
                line.clear();
                crate::push_csv_line(line, cells);
                w.write_all(line.as_bytes())
            }
            TableSink::Parquet(p) => p.push(cells),
        };
        written.map_err(|e| dir.failed(&self.rel, e))
    }

    /// Writes what is buffered and the end of the file.
    pub fn finish(self, dir: &OutDir) -> pedo_io::Result<()> {
        let mut w = match self.sink {
            TableSink::Csv { w, .. } => Ok(w),
            TableSink::Parquet(p) => p.finish_into_inner(),
        }
        .map_err(|e| dir.failed(&self.rel, e))?;
        w.flush().map_err(|e| dir.failed(&self.rel, e))
    }
}

/// `table` as the bytes of a Parquet file.
pub fn parquet_bytes(table: &Table) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let mut p = ParquetWriter::new(&mut bytes, &table.header);
    for row in &table.rows {
        p.push(row)?;
    }
    p.finish()?;
    Ok(bytes)
}

/// The type of a Parquet column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Int,
    Float,
    Text,
}

/// The type of a column with no value in its first row group, by its name: every text and
/// integer column of the run and study tables is named here (the rest are numbers), so that an
/// empty table has the types of a full one (Dask takes a study's types from its first file).
fn kind_of_empty(name: &str) -> Kind {
    match name {
        "status" | "reason" | "path" | "output" | "format" | "message" | "pressure_units" => {
            Kind::Text
        }
        // Ids, frames, nodes and counts of pairs, objects, matches, tracks, frames and the study.
        "id"
        | "id_a"
        | "id_b"
        | "object_id"
        | "track"
        | "step"
        | "index"
        | "frame"
        | "frame_a"
        | "frame_b"
        | "node"
        | "node_a"
        | "node_b"
        | "nodes"
        | "nodes_a"
        | "nodes_b"
        | "excess"
        | "trackable"
        | "tracked"
        | "contact_sensors"
        | "local_matches"
        | "trackable_matches"
        | "optimisation_matches"
        | "matches_after_excess"
        | "crossings"
        | "frames"
        | "pairs"
        | "tracks"
        | "stance"
        | "complete"
        | "percent" => Kind::Int,
        _ => Kind::Float,
    }
}

/// The buffered values of one column (nulls only in its definition levels).
enum Values {
    /// No value yet: the type is not known.
    Unknown,
    Int(Vec<i64>),
    Float(Vec<f64>),
    Text(Vec<ByteArray>),
}

impl Values {
    fn of(kind: Kind) -> Self {
        match kind {
            Kind::Int => Values::Int(Vec::new()),
            Kind::Float => Values::Float(Vec::new()),
            Kind::Text => Values::Text(Vec::new()),
        }
    }
    fn clear(&mut self) {
        match self {
            Values::Unknown => {}
            Values::Int(v) => v.clear(),
            Values::Float(v) => v.clear(),
            Values::Text(v) => v.clear(),
        }
    }
}

struct Column {
    name: String,
    values: Values,
    /// 1 for a value, 0 for a null, per buffered row.
    defined: Vec<i16>,
}

fn invalid(msg: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidData, msg)
}

fn parquet_error(e: parquet::errors::ParquetError) -> std::io::Error {
    std::io::Error::other(format!("parquet: {e}"))
}

/// A Parquet file written row by row: rows are buffered column by column and written as a row
/// group every [`ROW_GROUP_ROWS`] rows. The columns' types are fixed when the first row group is
/// written (see the module docs); a later value of another type is an error, except an integer
/// in a `DOUBLE` column.
pub struct ParquetWriter<W: Write + Send> {
    columns: Vec<Column>,
    rows: usize,
    sink: Option<W>,
    writer: Option<SerializedFileWriter<W>>,
    /// Scratch text for rounding numbers as the CSV writes them.
    text: String,
}

impl<W: Write + Send> ParquetWriter<W> {
    /// A file with these columns, written to `sink` (nothing is written before the first row
    /// group or [`ParquetWriter::finish`]).
    pub fn new(sink: W, header: &[String]) -> Self {
        Self {
            columns: header
                .iter()
                .map(|name| Column {
                    name: name.clone(),
                    values: Values::Unknown,
                    defined: Vec::new(),
                })
                .collect(),
            rows: 0,
            sink: Some(sink),
            writer: None,
            text: String::new(),
        }
    }

    /// Adds one row (a cell per column).
    pub fn push(&mut self, cells: &[Cell]) -> std::io::Result<()> {
        if cells.len() != self.columns.len() {
            return Err(invalid(format!(
                "a row of {} cells for {} columns",
                cells.len(),
                self.columns.len()
            )));
        }
        let fixed = self.writer.is_some();
        for (col, cell) in self.columns.iter_mut().zip(cells) {
            push_cell(col, cell, fixed, &mut self.text)?;
        }
        self.rows += 1;
        if self.rows >= ROW_GROUP_ROWS {
            self.write_group()?;
        }
        Ok(())
    }

    /// Writes the buffered rows and the file's footer.
    pub fn finish(self) -> std::io::Result<()> {
        self.finish_into_inner().map(drop)
    }

    /// [`ParquetWriter::finish`], giving back the sink (to flush it).
    pub fn finish_into_inner(mut self) -> std::io::Result<W> {
        if self.rows > 0 || self.writer.is_none() {
            self.write_group()?;
        }
        match self.writer.take() {
            Some(w) => w.into_inner().map_err(parquet_error),
            None => Err(invalid("parquet file not started".into())),
        }
    }

    /// Starts the file: fixes the columns' types and writes the header.
    fn open(&mut self) -> std::io::Result<()> {
        let mut fields = Vec::with_capacity(self.columns.len());
        for col in &mut self.columns {
            if let Values::Unknown = col.values {
                col.values = Values::of(kind_of_empty(&col.name));
            }
            let (physical, logical) = match col.values {
                Values::Int(_) => (PhysicalType::INT64, None),
                Values::Text(_) => (PhysicalType::BYTE_ARRAY, Some(LogicalType::String)),
                _ => (PhysicalType::DOUBLE, None),
            };
            let field = Type::primitive_type_builder(&col.name, physical)
                .with_repetition(Repetition::OPTIONAL)
                .with_logical_type(logical)
                .build()
                .map_err(parquet_error)?;
            fields.push(Arc::new(field));
        }
        let schema = Type::group_type_builder("schema")
            .with_fields(fields)
            .build()
            .map_err(parquet_error)?;
        let props = WriterProperties::builder()
            .set_compression(Compression::SNAPPY)
            .set_max_row_group_row_count(Some(ROW_GROUP_ROWS))
            .build();
        let sink = self
            .sink
            .take()
            .ok_or_else(|| invalid("parquet file already started".into()))?;
        self.writer = Some(
            SerializedFileWriter::new(sink, Arc::new(schema), Arc::new(props))
                .map_err(parquet_error)?,
        );
        Ok(())
    }

    /// Writes the buffered rows as one row group (none if there are no rows).
    fn write_group(&mut self) -> std::io::Result<()> {
        if self.writer.is_none() {
            self.open()?;
        }
        let Some(writer) = self.writer.as_mut() else {
            return Ok(());
        };
        if self.rows == 0 {
            return Ok(());
        }
        let mut group = writer.next_row_group().map_err(parquet_error)?;
        for col in &mut self.columns {
            let mut out = group
                .next_column()
                .map_err(parquet_error)?
                .ok_or_else(|| invalid(format!("parquet: no column for {}", col.name)))?;
            let defined = Some(col.defined.as_slice());
            let written = match &col.values {
                Values::Int(v) => out.typed::<Int64Type>().write_batch(v, defined, None),
                Values::Float(v) => out.typed::<DoubleType>().write_batch(v, defined, None),
                Values::Text(v) => out.typed::<ByteArrayType>().write_batch(v, defined, None),
                Values::Unknown => Ok(0),
            };
            written.map_err(parquet_error)?;
            out.close().map_err(parquet_error)?;
            col.values.clear();
            col.defined.clear();
        }
        group.close().map_err(parquet_error)?;
        self.rows = 0;
        Ok(())
    }
}

/// `v` as the CSV writes it with `decimals` (`format!("{v:.decimals$}")`), read back.
fn as_written(v: f64, decimals: usize, text: &mut String) -> f64 {
    use std::fmt::Write as _;
    if !v.is_finite() {
        return v;
    }
    text.clear();
    let _ = write!(text, "{v:.decimals$}");
    text.parse().unwrap_or(v)
}

fn push_cell(col: &mut Column, cell: &Cell, fixed: bool, text: &mut String) -> std::io::Result<()> {
    let mismatch = |what: &str| {
        invalid(format!(
            "table column {}: {what} after values of another type",
            col.name
        ))
    };
    match cell {
        Cell::Empty => {
            col.defined.push(0);
            return Ok(());
        }
        Cell::Int(v) => match &mut col.values {
            Values::Unknown => col.values = Values::Int(vec![*v]),
            Values::Int(vs) => vs.push(*v),
            Values::Float(vs) => vs.push(*v as f64),
            Values::Text(_) => return Err(mismatch("an integer")),
        },
        Cell::Float(v, d) => {
            let v = as_written(*v, *d, text);
            match &mut col.values {
                Values::Unknown => col.values = Values::Float(vec![v]),
                Values::Float(vs) => vs.push(v),
                // Integers so far: the column becomes numbers, unless its type is already fixed.
                Values::Int(vs) if !fixed => {
                    let mut f: Vec<f64> = vs.iter().map(|&i| i as f64).collect();
                    f.push(v);
                    col.values = Values::Float(f);
                }
                _ => return Err(mismatch("a number")),
            }
        }
        Cell::Text(s) => match &mut col.values {
            Values::Unknown => col.values = Values::Text(vec![ByteArray::from(s.as_str())]),
            Values::Text(vs) => vs.push(ByteArray::from(s.as_str())),
            _ => return Err(mismatch("text")),
        },
    }
    col.defined.push(1);
    Ok(())
}

/// The read-back helper the integration tests use too (one copy, not in the crate's API).
#[cfg(test)]
#[path = "../tests/common/parquet.rs"]
mod parquet_read_back;

#[cfg(test)]
mod tests {
    use super::*;
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::Field;

    /// The bytes as a file, opened for reading (a `bytes` dev-dependency would change the
    /// features `parquet` is built with, and so build it twice in CI).
    fn file(bytes: &[u8]) -> std::fs::File {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!("pedo-tables-{}-{n}.parquet", std::process::id()));
        std::fs::write(&path, bytes).unwrap();
        let f = std::fs::File::open(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        f
    }

    /// The bytes as a Parquet file read back: column names, rows, row groups.
    fn read_back(bytes: Vec<u8>) -> (Vec<String>, Vec<Vec<Field>>, usize) {
        parquet_read_back::read_back(file(&bytes))
    }

    #[test]
    fn cells_become_typed_nullable_columns_with_the_csv_values() {
        let table = Table {
            header: vec!["id".into(), "cost".into(), "status".into(), "reason".into()],
            rows: vec![
                vec![
                    Cell::Int(3),
                    Cell::Float(0.123456789, 6),
                    Cell::Text("ok".into()),
                    Cell::Empty,
                ],
                vec![
                    Cell::Int(-4),
                    Cell::Empty,
                    Cell::Text("skipped, \"no\" nodes".into()),
                    Cell::Empty,
                ],
                vec![
                    Cell::Empty,
                    Cell::Float(f64::NAN, 4),
                    Cell::Text("é".into()),
                    Cell::Empty,
                ],
            ],
        };
        let (names, rows, groups) = read_back(parquet_bytes(&table).unwrap());
        assert_eq!(names, table.header);
        assert_eq!(groups, 1);
        assert_eq!(rows.len(), 3);
        assert_eq!(
            rows[0],
            vec![
                Field::Long(3),
                Field::Double(0.123457),
                Field::Str("ok".into()),
                // An empty column gets the type of its name: text for a reason.
                Field::Null,
            ]
        );
        assert_eq!(rows[1][0], Field::Long(-4));
        assert_eq!(rows[1][1], Field::Null);
        assert_eq!(rows[1][2], Field::Str("skipped, \"no\" nodes".into()));
        assert_eq!(rows[2][0], Field::Null);
        assert!(matches!(rows[2][1], Field::Double(v) if v.is_nan()));
        let reader = SerializedFileReader::new(file(&parquet_bytes(&table).unwrap())).unwrap();
        let schema = reader.metadata().file_metadata().schema_descr_ptr();
        let types: Vec<_> = schema.columns().iter().map(|c| c.physical_type()).collect();
        assert_eq!(
            types,
            [
                PhysicalType::INT64,
                PhysicalType::DOUBLE,
                PhysicalType::BYTE_ARRAY,
                PhysicalType::BYTE_ARRAY
            ]
        );
        assert_eq!(
            schema.column(2).logical_type_ref(),
            Some(&LogicalType::String)
        );
        let compression = reader.metadata().row_group(0).column(1).compression();
        assert_eq!(compression, Compression::SNAPPY);
    }

    #[test]
    fn long_tables_are_written_in_bounded_row_groups() {
        let header = vec!["track".to_string(), "x".to_string()];
        let mut bytes = Vec::new();
        let mut w = ParquetWriter::new(&mut bytes, &header);
        let n = 2 * ROW_GROUP_ROWS + 10;
        for i in 0..n {
            w.push(&[Cell::Int(i as i64), Cell::Float(i as f64 / 8.0, 4)])
                .unwrap();
            // Never more than a row group buffered.
            assert!(w.columns[0].defined.len() < ROW_GROUP_ROWS);
        }
        w.finish().unwrap();
        let (_, rows, groups) = read_back(bytes);
        assert_eq!(groups, 3);
        assert_eq!(rows.len(), n);
        assert_eq!(
            rows[n - 1],
            vec![
                Field::Long(n as i64 - 1),
                Field::Double((n - 1) as f64 / 8.0)
            ]
        );
    }

    #[test]
    fn an_empty_table_is_a_file_with_its_columns() {
        let table = Table {
            header: vec!["id_a".into(), "message".into()],
            rows: vec![],
        };
        let (names, rows, groups) = read_back(parquet_bytes(&table).unwrap());
        assert_eq!((names, rows.len(), groups), (table.header, 0, 0));
    }

    #[test]
    fn a_value_of_another_type_after_the_first_row_group_is_an_error() {
        let header = vec!["v".to_string()];
        let mut bytes = Vec::new();
        let mut w = ParquetWriter::new(&mut bytes, &header);
        for i in 0..ROW_GROUP_ROWS {
            w.push(&[Cell::Int(i as i64)]).unwrap();
        }
        let err = w.push(&[Cell::Float(0.5, 1)]).unwrap_err().to_string();
        assert!(err.contains("column v"), "{err}");
        assert!(w.push(&[Cell::Int(1), Cell::Int(2)]).is_err());
    }

    #[test]
    fn the_option_reads_its_words() {
        assert_eq!(
            "parquet".parse::<TableFormat>().ok(),
            Some(TableFormat::Parquet)
        );
        let err = "xlsx".parse::<TableFormat>().unwrap_err().to_string();
        assert!(err.contains("tables") && err.contains("parquet"), "{err}");
        let names: Vec<_> = crate::output_option_specs()
            .iter()
            .map(|s| s.name)
            .collect();
        assert_eq!(
            names,
            [
                "figures",
                "figure_format",
                "tables",
                "report",
                "animation",
                "region_rule",
                "masks"
            ]
        );
        assert_eq!(TableFormat::default().file_name("matches"), "matches.csv");
    }
}
