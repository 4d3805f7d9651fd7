//! A Parquet file read back, for the tests of the Parquet tables: the unit tests of
//! `src/tables.rs` and the integration test `tests/parquet_tables.rs` include this one file
//! (with `#[path]`), so that it is not part of pedo-io's API.

use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::Field;

/// The file's column names, its rows (one field per column, in order) and its number of row
/// groups.
pub fn read_back(file: std::fs::File) -> (Vec<String>, Vec<Vec<Field>>, usize) {
    let reader = SerializedFileReader::new(file).unwrap();
    let groups = reader.metadata().num_row_groups();
    let names = reader
        .metadata()
        .file_metadata()
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let rows = reader
        .get_row_iter(None)
        .unwrap()
        .map(|r| {
            r.unwrap()
                .into_columns()
                .into_iter()
                .map(|(_, f)| f)
                .collect()
        })
        .collect();
    (names, rows, groups)
}
