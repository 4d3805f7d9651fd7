//! A recording's bytes read as a stream: decompressed as they are parsed (never whole first),
//! within the limits of [`crate::limits`], so that what a reader holds follows what it has
//! parsed, not what the file claims or expands to.

use crate::error::{IoError, Result};
use crate::limits::{current, raise};
use std::io::{self, BufRead, Read};

/// What bounds a stretch of a text format (see [`MAX_TOKEN_BYTES`](crate::limits::MAX_TOKEN_BYTES)): the byte that ends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stretch {
    /// A line of a text export, ended by `\n`.
    Line,
    /// XML text or markup, ended by the `<` of the next tag.
    Xml,
    /// JSON between two quotes (every key, every string).
    Json,
}

impl Stretch {
    fn end(self) -> u8 {
        match self {
            Stretch::Line => b'\n',
            Stretch::Xml => b'<',
            Stretch::Json => b'"',
        }
    }

    fn too_long(self, most: usize) -> String {
        let what = match self {
            Stretch::Line => "a line",
            Stretch::Xml => "text between two XML tags",
            Stretch::Json => "JSON between two quotes",
        };
        format!(
            "{what} longer than {most} bytes: no export of this format; {}",
            raise("max_text_mb")
        )
    }
}

/// A reader that fails (with [`io::ErrorKind::InvalidData`]) once more than its limit of bytes
/// have come through (what a compressed file may expand to), or a stretch of more than
/// [`MAX_TOKEN_BYTES`](crate::limits::MAX_TOKEN_BYTES) without its end byte (the limits [`current`] when it is made): a parser
/// above it never holds more.
pub(crate) struct Bounded<R> {
    inner: R,
    limit: Option<u64>,
    read: u64,
    stretch: Option<Stretch>,
    run: usize,
    /// The longest stretch allowed.
    most: usize,
    /// A JSON string's backslash escapes the byte after it (an escaped quote ends nothing).
    escaped: bool,
}

impl<R: Read> Bounded<R> {
    /// `inner` (decompressed already when `decompressed`: then at most [`MAX_DECOMPRESSED`](crate::limits::MAX_DECOMPRESSED)
    /// bytes), its stretches bounded when `stretch` is given.
    pub(crate) fn new(inner: R, decompressed: bool, stretch: Option<Stretch>) -> Self {
        let limits = current();
        Self {
            inner,
            limit: decompressed.then_some(limits.decompressed),
            read: 0,
            stretch,
            run: 0,
            most: limits.text,
            escaped: false,
        }
    }

    /// The run of a JSON string after `bytes`: only a quote no backslash escapes ends it.
    fn json_run(&mut self, bytes: &[u8]) -> usize {
        let mut run = self.run;
        for &b in bytes {
            run += 1;
            if self.escaped {
                self.escaped = false;
            } else if b == b'\\' {
                self.escaped = true;
            } else if b == b'"' {
                run = 0;
            }
        }
        run
    }
}

impl<R: Read> Read for Bounded<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        if let Some(limit) = self.limit.filter(|&l| self.read > l) {
            return Err(invalid(format!(
                "decompresses to more than {limit} bytes, the limit for a compressed recording; \
                 {}",
                raise("max_decompressed_mb")
            )));
        }
        let Some(stretch) = self.stretch else {
            return Ok(n);
        };
        self.run = match stretch {
            Stretch::Json => self.json_run(&buf[..n]),
            _ => match memchr::memrchr(stretch.end(), &buf[..n]) {
                Some(i) => n - 1 - i,
                None => self.run + n,
            },
        };
        if self.run > self.most {
            return Err(invalid(stretch.too_long(self.most)));
        }
        Ok(n)
    }
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg)
}

/// A gzip stream's decompressed bytes; a corrupt stream is [`io::ErrorKind::InvalidData`].
pub(crate) struct Gunzip<R: Read>(flate2::read::GzDecoder<R>);

impl<R: Read> Gunzip<R> {
    pub(crate) fn new(compressed: R) -> Self {
        Self(flate2::read::GzDecoder::new(compressed))
    }
}

impl<R: Read> Read for Gunzip<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.0
            .read(buf)
            .map_err(|e| invalid(format!("gzip stream: {e}")))
    }
}

/// The error of reading `name`: a stream refused as data (a limit of [`Bounded`], a corrupt
/// compressed stream) is a [`IoError::Format`], anything else what the system said.
pub(crate) fn read_error(name: &str, source: io::Error) -> IoError {
    if source.kind() == io::ErrorKind::InvalidData {
        IoError::format(name, source.to_string())
    } else {
        IoError::Io {
            path: name.to_string(),
            source,
        }
    }
}

/// The text lines of a stream with their 1-based numbers, read as Latin-1 (the vendors'
/// encoding; ASCII and UTF-8 bytewise) and without the line end (`\n` or `\r\n`): a last line
/// ended by a line break is followed by no empty line. A read error ends them and is kept in
/// `failure`.
pub(crate) struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    n: usize,
    failure: Option<io::Error>,
}

impl<R: BufRead> Iterator for Lines<R> {
    type Item = (usize, String);

    fn next(&mut self) -> Option<(usize, String)> {
        self.buf.clear();
        match self.reader.read_until(b'\n', &mut self.buf) {
            Ok(0) => None,
            Ok(_) => {
                let mut l = self.buf.strip_suffix(b"\n").unwrap_or(&self.buf);
                l = l.strip_suffix(b"\r").unwrap_or(l);
                self.n += 1;
                let text = match std::str::from_utf8(l) {
                    Ok(ascii) if l.is_ascii() => ascii.to_string(),
                    _ => l.iter().map(|&b| b as char).collect(),
                };
                Some((self.n, text))
            }
            Err(e) => {
                self.failure = Some(e);
                None
            }
        }
    }
}

/// Hands the lines of `reader` (see [`Lines`]) to `parse`; a read error (the system's, a corrupt
/// or oversized compressed stream, an overlong line) is returned instead of what `parse` makes
/// of the lines before it, which would only look cut short.
pub(crate) fn parse_lines<R: BufRead, T>(
    reader: R,
    name: &str,
    parse: impl FnOnce(&mut Lines<R>) -> Result<T>,
) -> Result<T> {
    let mut lines = Lines {
        reader,
        buf: Vec::new(),
        n: 0,
        failure: None,
    };
    let parsed = parse(&mut lines);
    match lines.failure.take() {
        Some(e) => Err(read_error(name, e)),
        None => parsed,
    }
}

/// A buffered reader over `decoded` (decompressed already when `decompressed`) bounded for
/// `stretch`, see [`Bounded`].
pub(crate) fn bounded<'a>(
    decoded: impl Read + 'a,
    decompressed: bool,
    stretch: Stretch,
) -> io::BufReader<Bounded<Box<dyn Read + 'a>>> {
    let inner: Box<dyn Read + 'a> = Box::new(decoded);
    io::BufReader::with_capacity(1 << 16, Bounded::new(inner, decompressed, Some(stretch)))
}

/// All of `decoded` (decompressed already when `decompressed`: then at most
/// [`MAX_DECOMPRESSED`](crate::limits::MAX_DECOMPRESSED) bytes), for the formats parsed whole.
pub(crate) fn read_all(decoded: impl Read, decompressed: bool, name: &str) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    Bounded::new(decoded, decompressed, None)
        .read_to_end(&mut bytes)
        .map_err(|e| read_error(name, e))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines_of(bytes: &[u8]) -> Vec<(usize, String)> {
        parse_lines(bounded(bytes, false, Stretch::Line), "m", |l| {
            Ok(l.collect())
        })
        .unwrap()
    }

    #[test]
    fn lines_are_cut_at_line_breaks_without_a_last_empty_line() {
        let strings = |v: &[&str]| -> Vec<(usize, String)> {
            v.iter()
                .enumerate()
                .map(|(i, s)| (i + 1, s.to_string()))
                .collect()
        };
        let cases: [(&[u8], &[&str]); 7] = [
            (b"", &[]),
            (b"\n", &[""]),
            (b"a", &["a"]),
            (b"a\n", &["a"]),
            (b"a\r\nb", &["a", "b"]),
            (b"a\n\nb\n\n", &["a", "", "b", ""]),
            (b"\xe9t\xe9\r\n", &["\u{e9}t\u{e9}"]),
        ];
        for (text, lines) in cases {
            assert_eq!(lines_of(text), strings(lines), "{text:?}");
        }
    }

    #[test]
    fn an_overlong_stretch_and_an_oversized_stream_are_format_errors() {
        let long = vec![b'0'; crate::limits::MAX_TOKEN_BYTES + 2];
        let e = parse_lines(bounded(&long[..], false, Stretch::Line), "l.csv", |l| {
            Ok(l.count())
        })
        .unwrap_err();
        assert!(matches!(e, IoError::Format { .. }), "{e}");
        assert!(
            e.to_string().starts_with("l.csv: a line longer than"),
            "{e}"
        );
        // Lines of the same total length pass.
        let mut short = long.clone();
        short[crate::limits::MAX_TOKEN_BYTES / 2] = b'\n';
        let n = parse_lines(bounded(&short[..], false, Stretch::Line), "s", |l| {
            Ok(l.count())
        });
        assert_eq!(n.unwrap(), 2);
        let gz = Gunzip::new(&b"\x1f\x8bnot gzip"[..]);
        let e = parse_lines(bounded(gz, true, Stretch::Line), "g", |l| Ok(l.count())).unwrap_err();
        assert!(e.to_string().starts_with("g: gzip stream:"), "{e}");
    }
}
