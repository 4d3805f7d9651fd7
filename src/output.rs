//! File input and output shared by the subcommands: small CSV readers and atomic writes.

use pedo_io::figure::{self, Figure};
use pedo_io::sequence::{SequenceOptions, SequenceResult};
use std::path::Path;

/// Reads a dense CSV matrix of f64 (comma, semicolon, tab or space separated; `inf`, `-inf` and
/// `nan` accepted so the solver can report them). Returns row-major values and the shape.
pub fn read_cost_csv(path: &Path) -> Result<(Vec<f64>, usize, usize), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut values = Vec::new();
    let mut cols = None;
    let mut rows = 0;
    for (lineno, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let start = values.len();
        for field in line.split([',', ';', '\t', ' ']) {
            let field = field.trim();
            if field.is_empty() {
                continue;
            }
            let v: f64 = field.parse().map_err(|_| {
                format!("{}:{}: not a number: {field:?}", path.display(), lineno + 1)
            })?;
            values.push(v);
        }
        let n = values.len() - start;
        match cols {
            None => cols = Some(n),
            Some(c) if c != n => {
                return Err(format!(
                    "{}:{}: row has {n} values, the first row has {c}",
                    path.display(),
                    lineno + 1
                ))
            }
            _ => {}
        }
        rows += 1;
    }
    Ok((values, rows, cols.unwrap_or(0)))
}

/// An output folder whose files appear all together or not at all: everything is written into a
/// hidden staging folder inside it and moved into place by [`OutDir::commit`]; a run that fails
/// half-way leaves the folder as it was.
pub struct OutDir {
    root: std::path::PathBuf,
    staging: std::path::PathBuf,
    written: std::sync::Mutex<Vec<String>>,
    committed: bool,
}

impl OutDir {
    pub fn create(root: &Path) -> Result<Self, String> {
        let staging = root.join(format!(".pedomatch-staging-{}", std::process::id()));
        std::fs::create_dir_all(&staging).map_err(|e| format!("{}: {e}", root.display()))?;
        Ok(Self {
            root: root.to_path_buf(),
            staging,
            written: Default::default(),
            committed: false,
        })
    }

    /// Writes `rel` (which may include sub-folders) into the staging folder.
    pub fn write(&self, rel: &str, contents: &[u8]) -> Result<(), String> {
        let path = self.staging.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
        }
        std::fs::write(&path, contents)
            .map_err(|e| format!("{}: {e}", self.root.join(rel).display()))?;
        self.written
            .lock()
            .expect("no panics while holding the lock")
            .push(rel.to_string());
        Ok(())
    }

    /// Moves every written file into place (each by an atomic rename).
    pub fn commit(mut self) -> Result<(), String> {
        let written = std::mem::take(
            &mut *self
                .written
                .lock()
                .expect("no panics while holding the lock"),
        );
        for rel in &written {
            let dest = self.root.join(rel);
            if let Some(parent) = dest.parent() {
                std::fs::create_dir_all(parent)
                    .map_err(|e| format!("{}: {e}", parent.display()))?;
            }
            std::fs::rename(self.staging.join(rel), &dest)
                .map_err(|e| format!("{}: {e}", dest.display()))?;
        }
        self.committed = true;
        let _ = std::fs::remove_dir_all(&self.staging);
        Ok(())
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

/// Formats a CSV table; fields are numbers or identifiers, so no quoting is needed.
pub fn csv_table(header: &[&str], rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        s.push_str(&r.join(","));
        s.push('\n');
    }
    s
}

/// Writes every table of a sequence run and its figures (the summary is written by the caller,
/// once the output time is known): pairs.csv/.json, objects.csv, matches.csv, tracks.csv,
/// frames.csv (the per-frame measures of the frames used), figures/.
pub fn write_sequence(
    dir: &OutDir,
    recording: &pedo_io::Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
    (png, svg): (bool, bool),
) -> Result<(), String> {
    use pedo_io::report;
    use rayon::prelude::*;
    let pairs = report::pairs_table(recording, r);
    dir.write("pairs.csv", pairs.to_csv().as_bytes())?;
    dir.write("pairs.json", pretty(&pairs.to_json())?.as_bytes())?;
    dir.write(
        "objects.csv",
        report::objects_table(recording, r).to_csv().as_bytes(),
    )?;
    dir.write(
        "matches.csv",
        report::matches_table(recording, r).to_csv().as_bytes(),
    )?;
    dir.write(
        "tracks.csv",
        report::tracks_table(recording, r).to_csv().as_bytes(),
    )?;
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let frames = report::frames_table(recording, threshold, start, end);
    dir.write("frames.csv", frames.to_csv().as_bytes())?;

    if png || svg {
        let figures: Vec<(String, Figure)> = r
            .pairs
            .par_iter()
            .map(|p| {
                let (oa, ob) = (&r.objects[p.a], &r.objects[p.b]);
                (
                    format!("figures/pair_{:04}_{:04}", oa.id, ob.id),
                    figure::match_figure(&oa.shape, &ob.shape, &p.result.pairs),
                )
            })
            .collect();
        figures
            .par_iter()
            .try_for_each(|(stem, f)| -> Result<(), String> {
                if png {
                    dir.write(&format!("{stem}.png"), &f.to_png())?;
                }
                if svg {
                    dir.write(&format!("{stem}.svg"), f.to_svg().as_bytes())?;
                }
                Ok(())
            })?;
        let tracks = figure::tracks_figure(r, &recording.peak_image(), 3, 40);
        if png {
            dir.write("tracks.png", &tracks.to_png())?;
        }
        if svg {
            dir.write("tracks.svg", tracks.to_svg().as_bytes())?;
        }
    }
    Ok(())
}

/// Pretty JSON with a final newline.
pub fn pretty<T: serde::Serialize>(v: &T) -> Result<String, String> {
    serde_json::to_string_pretty(v)
        .map(|mut s| {
            s.push('\n');
            s
        })
        .map_err(|e| e.to_string())
}
