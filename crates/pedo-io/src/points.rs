//! Point files: one node per line, `x,y` or `x,y,z` (comma, semicolon, tab or space separated),
//! an optional header line, `#` comments. The inverse of [`write_points`].

use crate::error::{IoError, Result};
use modal_core::{Shape, Topology};
use std::path::Path;

/// Parses point-file text (see the module docs). `name` is used in error messages.
pub fn parse_points(text: &str, name: &str, topology: Topology) -> Result<Shape> {
    let mut coords = Vec::new();
    let mut dim = None;
    let mut seen_data = false;
    for (i, line) in data_lines(text) {
        let fields = fields(line);
        let values: std::result::Result<Vec<f64>, _> =
            fields.iter().map(|f| f.parse::<f64>()).collect();
        let values = match values {
            Ok(v) => v,
            // A header is allowed before the first data line only.
            Err(_) if !seen_data => continue,
            Err(_) => {
                return Err(IoError::parse(
                    name,
                    i + 1,
                    format!("not numbers: {line:?}"),
                ));
            }
        };
        seen_data = true;
        match dim {
            None if values.len() == 2 || values.len() == 3 => dim = Some(values.len()),
            None => {
                return Err(IoError::parse(
                    name,
                    i + 1,
                    format!("expected 2 or 3 columns, got {}", values.len()),
                ));
            }
            Some(d) if d != values.len() => {
                return Err(IoError::parse(
                    name,
                    i + 1,
                    format!("expected {d} columns, got {}", values.len()),
                ));
            }
            _ => {}
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(IoError::parse(
                name,
                i + 1,
                format!("coordinate {v} is not finite"),
            ));
        }
        coords.extend(values);
    }
    let dim = dim.ok_or_else(|| IoError::format(name, "no points"))?;
    Ok(Shape::new(dim, coords, topology)?)
}

/// The lines that hold something, 0-based numbers beside them: a UTF-8 byte-order mark (as
/// spreadsheet programs write), blank lines and `#` comments left out, each line trimmed.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    text.lines()
        .map(str::trim)
        .enumerate()
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

fn fields(line: &str) -> Vec<&str> {
    line.split([',', ';', '\t', ' '])
        .filter(|f| !f.is_empty())
        .collect()
}

/// Whether `text` is laid out as a point file — every line has 2 or 3 fields, the first may be
/// a header — whatever the fields hold, so that a point file with a bad value gets the point
/// file's error instead of being taken for a pressure grid.
pub fn is_point_layout(text: &str) -> bool {
    let mut lines = data_lines(text).map(|(_, l)| fields(l).len());
    let Some(first) = lines.next() else {
        return false;
    };
    let mut rest = lines.peekable();
    let header_ok = (2..=3).contains(&first) || rest.peek().is_some();
    header_ok && rest.all(|n| (2..=3).contains(&n))
}

/// Reads a point file (see the module docs).
pub fn read_points(path: impl AsRef<Path>, topology: Topology) -> Result<Shape> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Io {
        path: name.clone(),
        source,
    })?;
    parse_points(&text, &name, topology)
}

/// Formats a shape as a point file with an `x,y[,z]` header.
pub fn write_points(shape: &Shape) -> String {
    let mut s = String::from(if shape.dim() == 3 { "x,y,z\n" } else { "x,y\n" });
    for i in 0..shape.len() {
        let row: Vec<String> = shape.point(i).iter().map(|v| v.to_string()).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let shape =
            Shape::from_points_3d(&[[0.5, 1.0, -2.0], [3.0, 4.25, 1e-3]], Topology::None).unwrap();
        let back = parse_points(&write_points(&shape), "mem", Topology::None).unwrap();
        assert_eq!(back, shape);
        let err = parse_points("x,y\n1,2\n3\n", "f.csv", Topology::None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("f.csv:3"), "{err}");
        let err = parse_points("1,2\nfoo,bar\n", "g.csv", Topology::None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("g.csv:2"), "{err}");
        assert!(parse_points("# nothing\n", "e.csv", Topology::None).is_err());
        assert!(parse_points("1,2,3,4\n", "w.csv", Topology::None).is_err());
        assert!(parse_points("1,nan\n", "n.csv", Topology::None).is_err());
        // A byte-order mark before a header or before the first point loses nothing.
        for text in ["\u{feff}x,y\n1,2\n3,4\n5,7\n", "\u{feff}1,2\n3,4\n5,7\n"] {
            let s = parse_points(text, "bom.csv", Topology::None).unwrap();
            assert_eq!((s.len(), s.point(0)), (3, &[1.0, 2.0][..]), "{text:?}");
        }
        // Laid out as points: 2 or 3 fields a line after an optional header, whatever they
        // hold; a pressure grid has more columns.
        assert!(is_point_layout("x,y\n1,2\n3,nan\n"));
        assert!(is_point_layout("\u{feff}1;2;3\n# c\n4;5;inf\n"));
        assert!(is_point_layout("frame 1 of 3\n1,2\n"));
        assert!(!is_point_layout("0,0,1,2\n0,3,4,0\n"));
        assert!(!is_point_layout("x,y\n1,2\n0,3,4,0\n"));
        assert!(!is_point_layout("a title of five words\n"));
        assert!(!is_point_layout(""));
    }
}
