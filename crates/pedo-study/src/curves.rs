//! A study's stance-normalised curves in one long table (`study_curves.csv` or
//! `study_curves.parquet`): every row of every recording folder's `curves` table
//! ([`pedo_output::curves_table`]), headed by the recording's `path` and `output` folder, ready
//! for 1-D statistics over the curves (spm1d: one curve per recording and stance).
//!
//! The table is made from the folders themselves, as the study table is from their
//! `summary.json`: a resumed or partial study lists the rows of every folder its study table
//! lists. It is written row by row to a staging file and renamed into place, so it appears
//! whole or not at all and never holds the study in memory.

use crate::StudyRow;
use pedo_io::{IoError, Result};
use pedo_output::{Cell, ParquetWriter, TableFormat, CURVES};
use std::io::Write;
use std::path::Path;

/// The study curves table's name (`study_curves.csv` or `.parquet`).
pub const STUDY_CURVES: &str = "study_curves";

/// The columns of the study curves table: the recording, then the columns of every folder's
/// curves table a recording may have (a recording without one of them, e.g. without pressure
/// units or a pitch, leaves it empty, so that a column never mixes units). More measures of a
/// stance are more columns. The regions' curves of folders run with a region rule or masks
/// (`forefoot_force_n`, ...) follow these ([`study_curves_columns`]).
pub const STUDY_CURVES_COLUMNS: [&str; 12] = [
    "path",
    "output",
    "stance",
    "complete",
    "percent",
    "contact_area_mm2",
    "total_force_n",
    "peak_pressure_kpa",
    "cop_x",
    "cop_y",
    "cop_x_mm",
    "cop_y_mm",
];

/// The curves table of a recording's folder, `curves.csv` or `curves.parquet` (whichever is
/// there, `tables`' first): its header and rows. `None` when the folder has neither (written
/// by a pedomatch before the curves) or it cannot be read.
fn folder_curves(folder: &Path, tables: TableFormat) -> Option<(Vec<String>, Vec<Vec<Cell>>)> {
    let other = match tables {
        TableFormat::Csv => TableFormat::Parquet,
        TableFormat::Parquet => TableFormat::Csv,
    };
    [tables, other].into_iter().find_map(|f| {
        let path = folder.join(f.file_name(CURVES));
        match f {
            TableFormat::Csv => read_csv(&path),
            TableFormat::Parquet => read_parquet(&path),
        }
    })
}

/// A curves CSV (numbers and empty fields; text in a pedar recording's `foot` column only).
fn read_csv(path: &Path) -> Option<(Vec<String>, Vec<Vec<Cell>>)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut lines = text.lines();
    let header: Vec<String> = lines.next()?.split(',').map(str::to_string).collect();
    let rows = lines
        .map(|line| {
            (line.split(',').zip(&header))
                .map(|(f, column)| {
                    if column == "foot" {
                        Some(Cell::Text(f.to_string()))
                    } else if f.is_empty() {
                        Some(Cell::Empty)
                    } else if let Ok(v) = f.parse::<i64>() {
                        Some(Cell::Int(v))
                    } else {
                        let decimals = f.split_once('.').map_or(0, |(_, d)| d.len());
                        f.parse::<f64>().ok().map(|v| Cell::Float(v, decimals))
                    }
                })
                .collect::<Option<Vec<Cell>>>()
        })
        .collect::<Option<Vec<_>>>()?;
    Some((header, rows))
}

/// A curves Parquet file, its numbers written back with the decimals of the CSV (4).
fn read_parquet(path: &Path) -> Option<(Vec<String>, Vec<Vec<Cell>>)> {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::Field;
    let reader = SerializedFileReader::new(std::fs::File::open(path).ok()?).ok()?;
    let header: Vec<String> = reader
        .metadata()
        .file_metadata()
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let mut rows = Vec::new();
    for row in reader.get_row_iter(None).ok()? {
        let row = row.ok()?;
        let cells = row
            .get_column_iter()
            .map(|(_, field)| match field {
                Field::Null => Some(Cell::Empty),
                Field::Long(v) => Some(Cell::Int(*v)),
                Field::Double(v) => Some(Cell::Float(*v, 4)),
                Field::Str(v) => Some(Cell::Text(v.clone())),
                _ => None,
            })
            .collect::<Option<Vec<Cell>>>()?;
        rows.push(cells);
    }
    Some((header, rows))
}

/// Where each of a folder's columns goes in the study table of columns `columns` (`None`: a
/// column it does not have, e.g. of a newer version).
fn placement(header: &[String], columns: &[String]) -> Vec<Option<usize>> {
    header
        .iter()
        .map(|h| columns.iter().position(|c| c == h))
        .collect()
}

/// Whether `column` of a folder's curves table is a region's curve: a force (`_force_n`, or a
/// load `_load_...`) or peak pressure (`_peak_pressure...`) column other than the frames'.
fn is_region_curve(column: &str) -> bool {
    !STUDY_CURVES_COLUMNS.contains(&column)
        && (column.ends_with("_force_n")
            || column.contains("_load_")
            || column.contains("_peak_pressure"))
}

/// The columns of the study curves table of `rows`' folders under `out`:
/// [`STUDY_CURVES_COLUMNS`] (with `foot` after `output` when a folder's curves are per foot, a
/// pedar recording's; empty for the others), then the region curve columns of the folders'
/// curves tables, in the order they first appear (a folder without them leaves them empty).
pub fn study_curves_columns(out: &Path, rows: &[StudyRow], tables: TableFormat) -> Vec<String> {
    let mut columns: Vec<String> = STUDY_CURVES_COLUMNS.iter().map(|s| s.to_string()).collect();
    let mut feet = false;
    for row in rows {
        let Some(output) = &row.output else { continue };
        let Some((cols, _)) = folder_curves(&out.join(output), tables) else {
            continue;
        };
        for c in cols {
            feet |= c == "foot";
            if is_region_curve(&c) && !columns.contains(&c) {
                columns.push(c);
            }
        }
    }
    if feet {
        columns.insert(2, "foot".to_string());
    }
    columns
}

/// Writes the curves of `rows`' folders under `out` (rows with a folder, in their order) as
/// `study_curves.csv` (or `.parquet`, as `tables` says), replacing it in one rename; the table
/// of the other format, left by an earlier run, is removed. A folder without a curves table
/// (written before pedomatch wrote one) adds no row.
pub fn write_study_curves(out: &Path, rows: &[StudyRow], tables: TableFormat) -> Result<()> {
    let name = tables.file_name(STUDY_CURVES);
    let target = out.join(&name);
    let tmp = out.join(format!(".{name}.tmp-{}", std::process::id()));
    let written = write_to(&tmp, out, rows, tables).and_then(|()| std::fs::rename(&tmp, &target));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(IoError::Io {
            path: target.display().to_string(),
            source: e,
        });
    }
    let other = match tables {
        TableFormat::Csv => TableFormat::Parquet,
        TableFormat::Parquet => TableFormat::Csv,
    };
    let _ = std::fs::remove_file(out.join(other.file_name(STUDY_CURVES)));
    Ok(())
}

/// The staging file of the study curves, CSV or Parquet, row by row.
enum RowSink {
    Csv(std::io::BufWriter<std::fs::File>),
    Parquet(Box<ParquetWriter<std::io::BufWriter<std::fs::File>>>),
}

impl RowSink {
    fn push(&mut self, cells: &[Cell]) -> std::io::Result<()> {
        match self {
            RowSink::Csv(w) => {
                let mut line = String::new();
                pedo_output::push_csv_line(&mut line, cells);
                w.write_all(line.as_bytes())
            }
            RowSink::Parquet(p) => p.push(cells),
        }
    }

    fn finish(self) -> std::io::Result<()> {
        match self {
            RowSink::Csv(mut w) => w.flush(),
            RowSink::Parquet(p) => p.finish_into_inner()?.flush(),
        }
    }
}

fn write_to(tmp: &Path, out: &Path, rows: &[StudyRow], tables: TableFormat) -> std::io::Result<()> {
    let header = study_curves_columns(out, rows, tables);
    let mut file = std::io::BufWriter::new(std::fs::File::create(tmp)?);
    let mut sink = match tables {
        TableFormat::Csv => {
            let mut line = header.join(",");
            line.push('\n');
            file.write_all(line.as_bytes())?;
            RowSink::Csv(file)
        }
        TableFormat::Parquet => RowSink::Parquet(Box::new(ParquetWriter::new(file, &header))),
    };
    for row in rows {
        let Some(output) = &row.output else { continue };
        let Some((cols, cells)) = folder_curves(&out.join(output), tables) else {
            continue;
        };
        let at = placement(&cols, &header);
        for r in cells {
            let mut full = vec![Cell::Empty; header.len()];
            full[0] = Cell::Text(row.path.clone());
            full[1] = Cell::Text(output.clone());
            for (cell, to) in r.into_iter().zip(&at) {
                if let Some(k) = to.filter(|&k| k > 1) {
                    full[k] = cell;
                }
            }
            sink.push(&full)?;
        }
    }
    sink.finish()?;
    std::fs::File::open(tmp)?.sync_all()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pedar_folders_foot_column_joins_the_study_curves_empty_for_the_others() {
        let out = std::env::temp_dir().join(format!("pedo-feet-{}", std::process::id()));
        let plate = "stance,complete,percent,peak_pressure_kpa\n0,1,0,1.5000\n";
        let pedar = "foot,stance,complete,percent,peak_pressure_kpa\n\
                     left,0,1,0,3.0000\nright,0,0,0,4.0000\n";
        let mut rows = Vec::new();
        for (name, csv) in [("plate", plate), ("pedar", pedar)] {
            std::fs::create_dir_all(out.join(name)).unwrap();
            std::fs::write(out.join(name).join("curves.csv"), csv).unwrap();
            let row = serde_json::json!({"path": name, "output": name, "wall_time_s": 0.0, "status": "ok"});
            rows.push(crate::row_from_json(&row).unwrap());
        }
        write_study_curves(&out, &rows, TableFormat::Csv).unwrap();
        let text = std::fs::read_to_string(out.join("study_curves.csv")).unwrap();
        let lines: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
        assert_eq!(lines[0][..4], ["path", "output", "foot", "stance"]);
        let at = |name: &str| lines[0].iter().position(|c| *c == name).unwrap();
        let (foot, area) = (at("foot"), at("peak_pressure_kpa"));
        let got: Vec<(&str, &str, &str)> = (lines[1..].iter())
            .map(|l| (l[0], l[foot], l[area]))
            .collect();
        assert_eq!(
            got,
            [
                ("plate", "", "1.5000"),
                ("pedar", "left", "3.0000"),
                ("pedar", "right", "4.0000")
            ]
        );
        // As Parquet too: the foot is a text column, empty for the plate.
        write_study_curves(&out, &rows, TableFormat::Parquet).unwrap();
        let (header, cells) = read_parquet(&out.join("study_curves.parquet")).unwrap();
        assert_eq!(header[2], "foot");
        let feet: Vec<Cell> = cells.iter().map(|r| r[2].clone()).collect();
        assert_eq!(
            feet,
            [
                Cell::Empty,
                Cell::Text("left".into()),
                Cell::Text("right".into())
            ]
        );
        std::fs::remove_dir_all(&out).unwrap();
    }
}
