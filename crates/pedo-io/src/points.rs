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
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split([',', ';', '\t', ' '])
            .filter(|f| !f.is_empty())
            .collect();
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
    }
}
