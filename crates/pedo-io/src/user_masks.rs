//! Region masks a user draws over the peak image (docs/measures.md, "Regions"): a label image
//! (`.npy`, a CSV grid, a PNG/TIFF image, or Python's 2-D array) of the recording's rows ×
//! columns, 0 = no region, each other integer one region named `region_<label>`; or a CSV of
//! polygons, one vertex a line, `region,x_mm,y_mm` (millimetres, sensel centres at
//! `(column × dx, row × dy)`, as the peak image's axes) or `region,x,y` (sensels, x = column,
//! y = row), each region's vertices in order and named by its `region` column. A sensel belongs
//! to a polygon when its centre lies inside it (even-odd rule); polygons may not overlap.
//!
//! The masks are [`RegionMasks`] without a rule: [`crate::regions::RegionSeries`] measures them
//! as it measures the automatic regions (peak pressure, PTI, FTI, contact area, contact time,
//! share of the impulse). Sensels outside every region belong to none: the masks need not cover
//! the footprint.

use crate::error::{IoError, Result};
use crate::marks::LabelMask;
use crate::regions::RegionMasks;
use std::path::Path;

/// The most regions a user's masks may hold (labels are stored as bytes).
pub const MAX_USER_REGIONS: usize = 255;

/// Whether `text`'s first line (blank lines and `#` comments skipped) is the header of a
/// polygons file: it names a `region` column.
pub fn is_polygon_csv(text: &str) -> bool {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    text.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .is_some_and(|h| {
            h.split([',', ';', '\t'])
                .any(|f| f.trim().trim_matches('"').eq_ignore_ascii_case("region"))
        })
}

/// One region of a polygons file: its name and vertices (x = column, y = row, in sensels).
#[derive(Debug, Clone, PartialEq)]
pub struct MaskPolygon {
    /// The region's name.
    pub name: String,
    /// Its vertices in sensels, in order (closed implicitly).
    pub vertices: Vec<[f64; 2]>,
}

/// Parses a polygons file (see the [module](self)): vertices in mm are turned into sensels by
/// `pitch_mm`. `name` is the file's name in errors.
///
/// # Errors
///
/// [`IoError::Format`] for a header without `region` and `x_mm,y_mm` (or `x,y`) columns, or a
/// file without vertices; [`IoError::Parse`] naming the line of a missing or non-finite value;
/// [`IoError::InvalidInput`] for millimetres without a pitch, or a region of fewer than three
/// vertices.
pub fn parse_mask_polygons(
    text: &str,
    name: &str,
    pitch_mm: Option<[f64; 2]>,
) -> Result<Vec<MaskPolygon>> {
    let table = crate::marks::HandTable::parse(text, name, "region,x_mm,y_mm")?;
    let (header, col) = (&table.header, |n: &str| table.col(n));
    let region =
        col("region").ok_or_else(|| IoError::format(name, "the header names no region column"))?;
    let (x, y, mm) = match (col("x_mm"), col("y_mm"), col("x"), col("y")) {
        (Some(x), Some(y), _, _) => (x, y, true),
        (_, _, Some(x), Some(y)) => (x, y, false),
        _ => {
            return Err(IoError::format(
                name,
                format!(
                    "the header names no x_mm,y_mm (mm) or x,y (sensels) columns: {}",
                    header.join(",")
                ),
            ));
        }
    };
    let scale = if mm {
        let p = pitch_mm.ok_or_else(|| {
            IoError::invalid(format!(
                "masks: {name} gives polygons in mm but the recording's pitch is unknown: \
                 give pitch_mm, or the vertices in sensels (x, y)"
            ))
        })?;
        [1.0 / p[0], 1.0 / p[1]]
    } else {
        [1.0, 1.0]
    };
    let mut out: Vec<MaskPolygon> = Vec::new();
    for row in table.rows() {
        let region = row.get(region, "region")?.clone();
        if region.is_empty() {
            return Err(IoError::parse(name, row.line, "the region has no name"));
        }
        let p = [
            row.number(x, "x")? * scale[0],
            row.number(y, "y")? * scale[1],
        ];
        match out.iter_mut().find(|r| r.name == region) {
            Some(r) => r.vertices.push(p),
            None => out.push(MaskPolygon {
                name: region,
                vertices: vec![p],
            }),
        }
    }
    if out.is_empty() {
        return Err(IoError::format(name, "no vertex under the header"));
    }
    if let Some(r) = out.iter().find(|r| r.vertices.len() < 3) {
        return Err(IoError::invalid(format!(
            "masks: region {:?} of {name} has {}: a polygon needs 3 or more",
            r.name,
            crate::counted(r.vertices.len(), "vertex")
        )));
    }
    Ok(out)
}

/// Whether point `p` lies inside polygon `v` (even-odd rule, half-open edges: a point on an
/// edge two polygons share lies in one of them).
fn inside(v: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut odd = false;
    let mut j = v.len() - 1;
    for i in 0..v.len() {
        let (a, b) = (v[i], v[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                odd = !odd;
            }
        }
        j = i;
    }
    odd
}

/// The masks of `polygons` over an image of `rows × cols` sensels: each sensel whose centre lies
/// inside a polygon is labelled with it (labels in the polygons' order).
///
/// # Errors
///
/// [`IoError::InvalidInput`] for more than [`MAX_USER_REGIONS`] regions, a region holding no
/// sensel centre of the image, or two regions holding the same sensel.
pub fn masks_of_polygons(
    polygons: &[MaskPolygon],
    rows: usize,
    cols: usize,
) -> Result<RegionMasks> {
    if polygons.len() > MAX_USER_REGIONS {
        return Err(IoError::invalid(format!(
            "masks: {} regions, at most {MAX_USER_REGIONS}",
            polygons.len()
        )));
    }
    let mut labels = vec![0u8; rows * cols];
    for (k, poly) in polygons.iter().enumerate() {
        let label = (k + 1) as u8;
        let mut any = false;
        for (i, l) in labels.iter_mut().enumerate() {
            let centre = [(i % cols) as f64, (i / cols) as f64];
            if !inside(&poly.vertices, centre) {
                continue;
            }
            if *l != 0 {
                return Err(IoError::invalid(format!(
                    "masks: regions {:?} and {:?} overlap at row {}, column {}",
                    polygons[usize::from(*l) - 1].name,
                    poly.name,
                    i / cols,
                    i % cols
                )));
            }
            *l = label;
            any = true;
        }
        if !any {
            return Err(IoError::invalid(format!(
                "masks: region {:?} holds no sensel centre of the {rows} × {cols} image",
                poly.name
            )));
        }
    }
    Ok(RegionMasks {
        rows,
        cols,
        labels,
        names: polygons.iter().map(|p| p.name.clone()).collect(),
        rule: None,
        axis: None,
        sides: Vec::new(),
        foot_axes: Vec::new(),
    })
}

/// The masks of a label image checked against frames of `rows × cols`: its labels in ascending
/// order become regions `region_<label>`.
///
/// # Errors
///
/// [`IoError::InvalidInput`] for an image of another shape, or more than
/// [`MAX_USER_REGIONS`] labels.
pub fn masks_of_labels(mask: &LabelMask, rows: usize, cols: usize) -> Result<RegionMasks> {
    if mask.shape() != (rows, cols) {
        return Err(IoError::invalid(format!(
            "masks: the label image is {} × {} (rows × columns), the recording's frames {rows} × {cols}",
            mask.shape().0,
            mask.shape().1
        )));
    }
    let found = mask.regions();
    if found.len() > MAX_USER_REGIONS {
        return Err(IoError::invalid(format!(
            "masks: {} labels, at most {MAX_USER_REGIONS} regions",
            found.len()
        )));
    }
    let mut labels = vec![0u8; rows * cols];
    for (k, &label) in found.iter().enumerate() {
        for (l, c) in labels.iter_mut().zip(mask.cells(label)) {
            if c {
                *l = (k + 1) as u8;
            }
        }
    }
    Ok(RegionMasks {
        rows,
        cols,
        labels,
        names: found.iter().map(|l| format!("region_{l}")).collect(),
        rule: None,
        axis: None,
        sides: Vec::new(),
        foot_axes: Vec::new(),
    })
}

/// Reads the masks file at `path` for frames of `rows × cols` sensels `pitch_mm` apart: a
/// polygons CSV (its first line names a `region` column), else a label image (any file a
/// recording is read from holding one frame, [`LabelMask::read`]).
///
/// # Errors
///
/// Those of [`parse_mask_polygons`], [`masks_of_polygons`], [`LabelMask::read`] and
/// [`masks_of_labels`].
pub fn read_user_masks(
    path: impl AsRef<Path>,
    rows: usize,
    cols: usize,
    pitch_mm: Option<[f64; 2]>,
) -> Result<RegionMasks> {
    let path = path.as_ref();
    // A polygons file is short text; a label image may be binary or large.
    if let Ok(text) = std::fs::read_to_string(path)
        && is_polygon_csv(&text)
    {
        let name = path.display().to_string();
        let polygons = parse_mask_polygons(&text, &name, pitch_mm)?;
        return masks_of_polygons(&polygons, rows, cols);
    }
    masks_of_labels(&LabelMask::read(path)?, rows, cols)
}

/// The masks of a label image given as rows of numbers (Python's 2-D array), as
/// [`masks_of_labels`].
///
/// # Errors
///
/// Those of [`LabelMask::of_rows`] and [`masks_of_labels`].
pub fn user_masks_of_rows(values: &[Vec<f64>], rows: usize, cols: usize) -> Result<RegionMasks> {
    masks_of_labels(&LabelMask::of_rows(values)?, rows, cols)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygons_in_mm_label_the_sensels_whose_centres_they_hold() {
        // 4 × 6 sensels of 2 × 3 mm: "heel" the columns 0..=2 (x 0..4 mm), "toes" 3..=5.
        let text = "# two halves\nregion,x_mm,y_mm\nheel,-1,-1\nheel,5,-1\nheel,5,10\nheel,-1,10\n\
                    toes,5,-1\ntoes,11,-1\ntoes,11,10\ntoes,5,10\n";
        assert!(is_polygon_csv(text));
        let p = parse_mask_polygons(text, "m.csv", Some([2.0, 3.0])).unwrap();
        assert_eq!(p[0].vertices[1], [2.5, -1.0 / 3.0]);
        let m = masks_of_polygons(&p, 4, 6).unwrap();
        assert_eq!(m.names, ["heel", "toes"]);
        for r in 0..4 {
            assert_eq!(m.labels[r * 6..r * 6 + 6], [1, 1, 1, 2, 2, 2], "row {r}");
        }
        assert_eq!(m.rule, None);
        // A triangle in sensels: centres (0,0), (1,0), (0,1) inside, (1,1) on its edge outside.
        let tri = parse_mask_polygons(
            "region,x,y\nt,-0.5,-0.5\nt,2.5,-0.5\nt,-0.5,2.5\n",
            "t",
            None,
        )
        .unwrap();
        let m = masks_of_polygons(&tri, 2, 2).unwrap();
        assert_eq!(m.labels, [1, 1, 1, 0]);
    }

    #[test]
    fn bad_polygons_are_typed_errors() {
        let mm = "region,x_mm,y_mm\na,0,0\na,1,0\na,1,1\n";
        let e = parse_mask_polygons(mm, "m.csv", None).unwrap_err();
        assert!(e.to_string().contains("pitch"), "{e}");
        let e = parse_mask_polygons("region,x,y\na,0,0\na,1,0\n", "m.csv", None).unwrap_err();
        assert!(e.to_string().contains("3 or more"), "{e}");
        let e = parse_mask_polygons("region,x,y\na,0,zero\n", "m.csv", None).unwrap_err();
        assert!(matches!(e, IoError::Parse { .. }), "{e}");
        let e = parse_mask_polygons("region,u,v\na,0,0\n", "m.csv", None).unwrap_err();
        assert!(matches!(e, IoError::Format { .. }), "{e}");
        // Overlapping and empty regions.
        let two = "region,x,y\na,-1,-1\na,3,-1\na,3,3\nb,0.5,-1\nb,9,-1\nb,9,3\nb,0.5,3\n";
        let p = parse_mask_polygons(two, "m", None).unwrap();
        let e = masks_of_polygons(&p, 2, 2).unwrap_err();
        assert!(e.to_string().contains("overlap"), "{e}");
        let far =
            parse_mask_polygons("region,x,y\nf,50,50\nf,60,50\nf,60,60\n", "m", None).unwrap();
        let e = masks_of_polygons(&far, 2, 2).unwrap_err();
        assert!(e.to_string().contains("no sensel"), "{e}");
    }

    #[test]
    fn label_images_must_have_the_frames_shape() {
        let rows = vec![vec![0.0, 7.0, 7.0], vec![2.0, 0.0, 7.0]];
        let m = user_masks_of_rows(&rows, 2, 3).unwrap();
        assert_eq!(m.names, ["region_2", "region_7"]);
        assert_eq!(m.labels, [0, 2, 2, 1, 0, 2]);
        let e = user_masks_of_rows(&rows, 3, 2).unwrap_err();
        assert!(matches!(e, IoError::InvalidInput(_)), "{e}");
        assert!(e.to_string().contains("2 × 3"), "{e}");
        assert!(user_masks_of_rows(&[vec![0.5]], 1, 1).is_err());
        assert!(!is_polygon_csv("1,2,3\n4,5,6\n"));
    }
}
