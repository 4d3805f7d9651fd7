//! File input and output shared by the subcommands: small CSV readers and atomic writes.

use std::path::Path;

/// Writes to standard output. Every subcommand prints only once its outputs are complete, so a
/// reader that has gone (`pedomatch inspect … | head -3`) leaves nothing undone: the process
/// ends quietly with success, as `head` expects, instead of panicking. Any other failure to
/// write is a runtime error (exit code 1).
///
/// Control characters other than line breaks and tabs are escaped ([`terminal_safe`]).
pub fn write_stdout(args: std::fmt::Arguments) {
    use std::io::Write;
    let text = args.to_string();
    let mut out = std::io::stdout().lock();
    let text = terminal_safe(&text, true);
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("pedomatch: error: cannot write to standard output: {e}");
        std::process::exit(1);
    }
}

/// `text` with its control characters escaped as Rust escapes them (`\u{1b}`, `\r`; line breaks
/// and tabs too unless `multiline`): a file name (or a message quoting one) printed to a
/// terminal cannot move the cursor, recolour, retitle or clear it.
pub fn terminal_safe(text: &str, multiline: bool) -> std::borrow::Cow<'_, str> {
    let kept = |c: char| multiline && (c == '\n' || c == '\t');
    if !text.chars().any(|c| c.is_control() && !kept(c)) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        if c.is_control() && !kept(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// Writes one line to standard error (a message, an error naming a file), its control
/// characters escaped ([`terminal_safe`]).
pub fn error_line(line: &str) {
    eprintln!("{}", terminal_safe(line, false));
}

/// Reads a dense CSV matrix of f64 (comma, semicolon, tab or space separated; `inf`, `-inf` and
/// `nan` accepted so the solver can report them). Returns row-major values and the shape; a file
/// without a number is an error.
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
                ));
            }
            _ => {}
        }
        rows += 1;
    }
    if values.is_empty() {
        return Err(format!(
            "{}: no cost matrix: the file holds no numbers",
            path.display()
        ));
    }
    Ok((values, rows, cols.unwrap_or(0)))
}

/// An output folder being written (see [`pedo_output::outdir`]), with `String` errors.
pub struct OutDir(pub pedo_output::outdir::OutDir);

impl OutDir {
    /// Starts an output into `root`. Fails if `root` is a file, or a non-empty folder that is not
    /// a pedomatch output.
    pub fn create(root: &Path) -> Result<Self, String> {
        pedo_output::outdir::OutDir::create(root)
            .map(Self)
            .map_err(|e| e.to_string())
    }

    /// Writes `rel` (which may include sub-folders) into the staging folder.
    pub fn write(&self, rel: &str, contents: &[u8]) -> Result<(), String> {
        self.0.write(rel, contents).map_err(|e| e.to_string())
    }

    /// Puts the complete folder in place of the previous one in one step.
    pub fn commit(self) -> Result<(), String> {
        self.0.commit().map_err(|e| e.to_string())
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

/// "`DIR/` (file, file, ...)": an output folder and the files and folders it holds, for the
/// closing line of a command (the folder as given, with one trailing slash).
pub fn folder_text(dir: &Path) -> String {
    let shown = dir.display().to_string();
    let shown = shown.trim_end_matches('/');
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
                .map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if e.path().is_dir() {
                        name + "/"
                    } else {
                        name
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    format!("{shown}/ ({})", names.join(", "))
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
/// Writes `{stem}.png` and/or `{stem}.svg`.
pub fn write_figure(
    dir: &OutDir,
    stem: &str,
    kinds: pedo_output::FigureKinds,
    to_png: impl FnOnce() -> pedo_io::Result<Vec<u8>>,
    to_svg: impl FnOnce() -> pedo_io::Result<String>,
) -> Result<(), String> {
    pedo_output::write_figure(&dir.0, stem, kinds, to_png, to_svg).map_err(|e| e.to_string())
}
