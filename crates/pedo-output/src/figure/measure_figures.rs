//! The figures of a recording's measures ([`pedo_io::measures`]): the peak-pressure and the
//! pressure-time-integral images, drawn like the other figures (axes in mm when the pitch is
//! known, a colour bar with the units, the bundled font).

use super::*;
use pedo_io::measures::Measures;

/// Which image of [`Measures`] a [`MeasureFigure`] draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeasureImage {
    /// The peak-pressure image ([`Measures::peak`]).
    Peak,
    /// The pressure-time-integral image ([`Measures::pti`]).
    Pti,
}

impl MeasureImage {
    /// The file stem the run folder writes it as: `peak` or `pti` (`peak.png`, `pti.png`).
    pub fn stem(self) -> &'static str {
        match self {
            MeasureImage::Peak => "peak",
            MeasureImage::Pti => "pti",
        }
    }
}

/// One image of a recording's measures over its sensels, coloured by value with its colour bar.
#[derive(Debug, Clone)]
pub struct MeasureFigure<'a> {
    /// The measures drawn.
    pub measures: &'a Measures,
    /// Which of their images.
    pub image: MeasureImage,
    /// The recording's scale and timing ([`FigureAxes::of_recording`]).
    pub axes: &'a FigureAxes,
}

impl MeasureFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        render_png(&self.layout()?)
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        render_svg(&self.layout()?)
    }

    fn layout(&self) -> Result<Layout> {
        let m = self.measures;
        let (values, what, unit, top) = match self.image {
            MeasureImage::Peak => (
                &m.peak,
                "peak pressure",
                m.units.pressure.clone(),
                m.values.peak_pressure,
            ),
            MeasureImage::Pti => (
                &m.pti,
                "pressure-time integral",
                format!("{}·{}", m.units.pressure, m.units.time),
                m.values.pti_max,
            ),
        };
        if values.len() != m.rows * m.cols {
            return Err(IoError::invalid(
                "the measure image does not fill its rows and columns",
            ));
        }
        let corner = |c: f64, r: f64| self.axes.to_plot([c, r]);
        let mut bounds = Bounds::of([
            corner(-0.5, -0.5),
            corner(m.cols as f64 - 0.5, m.rows as f64 - 0.5),
        ])
        .ok_or_else(|| IoError::invalid("the measure image has no finite extent"))?;
        bounds.pad = false;
        let cells: Vec<([(f64, f64); 2], f64)> = (0..m.rows * m.cols)
            .filter(|&i| values[i].is_finite() && values[i] > 0.0)
            .map(|i| {
                let (row, col) = ((i / m.cols) as f64, (i % m.cols) as f64);
                let (x0, y0) = corner(col - 0.5, row - 0.5);
                let (x1, y1) = corner(col + 0.5, row + 0.5);
                ([(x0, y0), (x1, y1)], values[i])
            })
            .collect();
        let image = (top.is_finite() && top > 0.0).then(|| PressureImage {
            cells,
            max: top,
            label: format!("{what} ({unit})"),
            marks: Vec::new(),
        });
        let frames = match (
            self.axes.time_s(m.frames.start),
            self.axes.time_s(m.frames.end),
        ) {
            (Some(t0), Some(t1)) => format!(
                "frames {}\u{2013}{} ({t0:.3}\u{2013}{t1:.3} s)",
                m.frames.start,
                m.frames.end - 1
            ),
            _ => format!("frames {}\u{2013}{}", m.frames.start, m.frames.end - 1),
        };
        let mut title = what.to_string();
        if let Some(first) = title.get_mut(0..1) {
            first.make_ascii_uppercase();
        }
        let subtitle = format!("{frames}; maximum {} {unit}", format_value(top));
        Ok(Layout::new(
            bounds,
            self.axes,
            title,
            subtitle,
            Vec::new(),
            image,
            Vec::new(),
        ))
    }
}

/// The regions of a footprint over its peak-pressure image: each region's outline in its own
/// colour, named in the legend, and the foot's axis heel → toe (dashed).
#[derive(Debug, Clone)]
pub struct RegionFigure<'a> {
    /// The measures whose peak image is drawn.
    pub measures: &'a Measures,
    /// The regions.
    pub masks: &'a pedo_io::regions::RegionMasks,
    /// The recording's scale ([`FigureAxes::of_recording`]).
    pub axes: &'a FigureAxes,
}

impl RegionFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        render_png(&self.layout()?)
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        render_svg(&self.layout()?)
    }

    fn layout(&self) -> Result<Layout> {
        let (m, masks) = (self.measures, self.masks);
        if masks.rows != m.rows || masks.cols != m.cols || masks.labels.len() != m.rows * m.cols {
            return Err(IoError::invalid(
                "the region masks do not fit the peak image",
            ));
        }
        let mut layout = MeasureFigure {
            measures: m,
            image: MeasureImage::Peak,
            axes: self.axes,
        }
        .layout()?;
        // Each name its colour: both feet's regions of one name alike.
        let mut names: Vec<&str> = Vec::new();
        for n in &masks.names {
            if !names.contains(&n.as_str()) {
                names.push(n);
            }
        }
        let colour_of = |k: usize| {
            let j = names.iter().position(|n| *n == masks.names[k]).unwrap_or(k);
            TRACK_PALETTE[j % TRACK_PALETTE.len()]
        };
        let (rows, cols) = (m.rows as isize, m.cols as isize);
        let label = |r: isize, c: isize| {
            if r < 0 || c < 0 || r >= rows || c >= cols {
                0
            } else {
                masks.labels[(r * cols + c) as usize]
            }
        };
        let mut layers = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                let l = label(r, c);
                if l == 0 {
                    continue;
                }
                let (x, y) = (c as f64, r as f64);
                // The cell's edges bordering another region or the outside.
                let edges = [
                    (label(r - 1, c), [x - 0.5, y - 0.5], [x + 0.5, y - 0.5]),
                    (label(r + 1, c), [x - 0.5, y + 0.5], [x + 0.5, y + 0.5]),
                    (label(r, c - 1), [x - 0.5, y - 0.5], [x - 0.5, y + 0.5]),
                    (label(r, c + 1), [x + 0.5, y - 0.5], [x + 0.5, y + 0.5]),
                ];
                for (other, a, b) in edges {
                    if other != l {
                        layers.push(Layer::Line {
                            points: vec![self.axes.to_plot(a), self.axes.to_plot(b)],
                            color: colour_of(usize::from(l) - 1),
                            width: 2,
                        });
                    }
                }
            }
        }
        let mut legend: Vec<LegendEntry> = (names.iter().enumerate())
            .map(|(k, name)| LegendEntry {
                text: name.replace('_', " "),
                glyph: Glyph::Line(TRACK_PALETTE[k % TRACK_PALETTE.len()]),
            })
            .collect();
        let feet = masks.foot_axes.iter().map(|(_, a)| a);
        for axis in masks.axis.iter().chain(feet) {
            // The axis is in mm; the figure's points are in sensels.
            let pitch = self.axes.pitch_mm.unwrap_or([1.0, 1.0]);
            let at = |p: [f64; 2]| self.axes.to_plot([p[0] / pitch[0], p[1] / pitch[1]]);
            layers.push(Layer::Dashed {
                points: vec![at(axis.heel), at(axis.toe)],
                color: COLOR_UNMATCHED,
            });
            legend.push(LegendEntry {
                text: format!("foot axis, heel to toe ({} foot)", axis.side.name()),
                glyph: Glyph::Dashed(COLOR_UNMATCHED),
            });
        }
        let rule = masks.rule.map_or("user", |r| r.name());
        layout.title = format!("Regions ({rule}) over the peak pressure");
        layout.subtitle = if masks.sides.is_empty() {
            format!(
                "{} of the footprint",
                pedo_io::counted(masks.names.len(), "region")
            )
        } else {
            format!(
                "{} of each foot's footprint",
                pedo_io::counted(names.len(), "region")
            )
        };
        layout.legend = legend;
        layout.layers = layers;
        Ok(layout)
    }
}

/// A value with four significant digits, as a subtitle states it.
pub(super) fn format_value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use pedo_io::Recording;

    #[test]
    fn peak_and_pti_figures_have_colour_bars_with_units_and_mm_axes() {
        let data: Vec<f32> = (0..2 * 6 * 4).map(|i| (i % 7) as f32 * 10.0).collect();
        let rec = Recording::new(2, 6, 4, data, vec![true; 24])
            .unwrap()
            .with_pitch_mm([5.0, 5.0])
            .unwrap()
            .with_frame_rate(100.0)
            .unwrap()
            .with_units("kPa");
        let m = Measures::of_recording(&rec, 0.0, 0..2).unwrap();
        let axes = FigureAxes::of_recording(&rec);
        let svg = |image| {
            MeasureFigure {
                measures: &m,
                image,
                axes: &axes,
            }
            .to_svg()
            .unwrap()
        };
        let peak = svg(MeasureImage::Peak);
        assert!(peak.contains("peak pressure (kPa)"), "colour bar label");
        assert!(peak.contains("x (mm)") && peak.contains("y (mm)"));
        assert!(peak.contains("Peak pressure"));
        let pti = svg(MeasureImage::Pti);
        assert!(pti.contains("pressure-time integral (kPa·s)"));
        let png = MeasureFigure {
            measures: &m,
            image: MeasureImage::Pti,
            axes: &axes,
        }
        .to_png()
        .unwrap();
        assert!(png.starts_with(b"\x89PNG"));
        assert_eq!(format_value(812.345), "812.3");
        assert_eq!(format_value(0.012345), "0.01235");
    }

    #[test]
    fn the_regions_figure_outlines_each_region_and_names_it() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../pedo-io/tests/data/synthetic-walk.lst"
        );
        let rec = pedo_io::read_recording(path).unwrap();
        let n = rec.n_frames();
        let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
        let (masks, _) = pedo_io::regions::recording_regions(
            &rec,
            0.0,
            0..n,
            pedo_io::regions::RegionRule::Fine,
        )
        .unwrap();
        let axes = FigureAxes::of_recording(&rec);
        let fig = RegionFigure {
            measures: &m,
            masks: &masks,
            axes: &axes,
        };
        let svg = fig.to_svg().unwrap();
        for name in [
            "heel medial",
            "mh3 5",
            "lesser toes",
            "foot axis",
            "Regions (fine)",
        ] {
            assert!(svg.contains(name), "{name}");
        }
        assert!(fig.to_png().unwrap().starts_with(b"\x89PNG"));
        // Masks of another size are an error, not a panic.
        let mut wrong = masks.clone();
        wrong.rows += 1;
        let fig = RegionFigure {
            measures: &m,
            masks: &wrong,
            axes: &axes,
        };
        assert!(fig.to_svg().is_err());
    }
}
