//! File input and output shared by the subcommands: small CSV readers and atomic writes.

use std::io::Write;
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
        for field in line.split(|c: char| c == ',' || c == ';' || c == '\t' || c == ' ') {
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

/// Writes `contents` to `path` through a temporary file in the same folder and a rename, so a
/// reader never sees a half-written file.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), String> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().ok_or_else(|| format!("{}: not a file path", path.display()))?;
    let tmp = dir.join(format!(".{}.tmp{}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(contents)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: {e}", path.display())
    })
}
