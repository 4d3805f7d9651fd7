//! The stance-normalised curves of a recording ([`pedo_io::measures::StanceCurves`]): force,
//! contact area and peak pressure over 0–100 % of each stance, every stance a thin line, their
//! mean with a band of ± one standard deviation (`stance_curves.png` or `.svg`).

use super::*;
use pedo_io::measures::Measures;
use pedo_io::stances::CURVE_POINTS;

/// The colour of each stance's own line.
const COLOR_STANCE: RGBColor = RGBColor(170, 170, 170);

/// The width of the legend column of a stance curves figure, in pixels.
const STANCE_LEGEND_WIDTH: u32 = 230;

/// The stance-normalised curves of a recording's stances, one panel per quantity (force,
/// contact area, peak pressure) over 0–100 % of contact: each stance as a thin grey line, the
/// mean of the complete stances (of every stance when none is complete) with a band of ± one
/// standard deviation (the sample's, n − 1; no band for a single stance).
#[derive(Debug, Clone)]
pub struct StanceCurvesFigure<'a> {
    /// The measures whose stances are drawn.
    pub measures: &'a Measures,
}

/// The mean and sample standard deviation of `curves` at each point (the deviation 0 for fewer
/// than two curves).
pub fn mean_and_sd(curves: &[&[f64]]) -> (Vec<f64>, Vec<f64>) {
    let n = curves.len();
    let points = curves.first().map_or(0, |c| c.len());
    (0..points)
        .map(|p| {
            let mean = curves.iter().map(|c| c[p]).sum::<f64>() / n.max(1) as f64;
            let sd = if n > 1 {
                let ss: f64 = curves.iter().map(|c| (c[p] - mean).powi(2)).sum();
                (ss / (n - 1) as f64).sqrt()
            } else {
                0.0
            };
            (mean, sd)
        })
        .unzip()
}

impl StanceCurvesFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        render_png(&self.layout())
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        render_svg(&self.layout())
    }

    fn layout(&self) -> StanceCurvesLayout {
        let m = self.measures;
        let u = &m.units;
        // Both feet apart: each foot's own stances, as curves.csv has them.
        let stances = m.curve_stances();
        let complete: Vec<usize> = (0..stances.len())
            .filter(|&k| stances[k].stance.complete)
            .collect();
        let averaged: Vec<usize> = if complete.is_empty() {
            (0..stances.len()).collect()
        } else {
            complete.clone()
        };
        let load = if u.is_force { "force" } else { "load" };
        type Pick = fn(&pedo_io::measures::StanceCurves) -> &[f64];
        let quantities: [(String, Pick); 3] = [
            (format!("{load} ({})", u.force), |c| &c.force),
            (format!("contact area ({})", u.area), |c| &c.area),
            (format!("peak pressure ({})", u.pressure), |c| {
                &c.peak_pressure
            }),
        ];
        let panels = quantities
            .into_iter()
            .map(|(label, pick)| {
                let each: Vec<Vec<f64>> =
                    stances.iter().map(|s| pick(&s.curves).to_vec()).collect();
                let chosen: Vec<&[f64]> = averaged.iter().map(|&k| each[k].as_slice()).collect();
                let (mean, sd) = mean_and_sd(&chosen);
                StancePanel {
                    label,
                    each,
                    mean,
                    sd,
                }
            })
            .collect();
        let n = stances.len();
        let feet = if m.feet.is_empty() {
            ""
        } else {
            " of both feet"
        };
        let subtitle = if n == 0 {
            "no stance among the frames".to_string()
        } else if complete.is_empty() {
            format!(
                "{}{feet}, none complete: mean ± SD of all",
                pedo_io::counted(n, "stance")
            )
        } else {
            format!(
                "{}{feet}; mean ± SD of the {} complete",
                pedo_io::counted(n, "stance"),
                complete.len()
            )
        };
        StanceCurvesLayout {
            title: "Curves over the stance, 0\u{2013}100 % of contact".to_string(),
            subtitle,
            panels,
            band: averaged.len() > 1,
        }
    }
}

struct StancePanel {
    label: String,
    each: Vec<Vec<f64>>,
    mean: Vec<f64>,
    sd: Vec<f64>,
}

struct StanceCurvesLayout {
    title: String,
    subtitle: String,
    panels: Vec<StancePanel>,
    band: bool,
}

impl Drawing for StanceCurvesLayout {
    fn size(&self) -> (u32, u32) {
        let panels = self.panels.len() as u32;
        let width = (Y_LABEL_AREA + 24 + CURVE_PLOT.0 + 2 * PLOT_MARGIN + STANCE_LEGEND_WIDTH).max(
            text_width(&self.title, TITLE_SIZE).max(text_width(&self.subtitle, SUBTITLE_SIZE))
                + 2 * TITLE_MARGIN,
        );
        let height = TITLE_HEIGHT + panels * (CURVE_PLOT.1 + PLOT_MARGIN) + X_LABEL_AREA;
        (width.min(MAX_SIDE), height.min(MAX_SIDE))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(figure_error)?;
        let (w, h) = root.dim_in_pixel();
        let (top, body) = root.split_vertically(TITLE_HEIGHT);
        draw_title(&top, w, &self.title, &self.subtitle)?;
        let (plots, legend) = body.split_horizontally(w.saturating_sub(STANCE_LEGEND_WIDTH));
        let mut entries = vec![
            LegendEntry {
                text: "each stance".to_string(),
                glyph: Glyph::Line(COLOR_STANCE),
            },
            LegendEntry {
                text: "mean".to_string(),
                glyph: Glyph::Line(COLOR_A),
            },
        ];
        if self.band {
            entries.push(LegendEntry {
                text: "mean \u{b1} 1 SD".to_string(),
                glyph: Glyph::Dashed(COLOR_A),
            });
        }
        draw_legend(&legend.margin(8, 0, 0, 0), &entries)?;
        let x: Vec<f64> = (0..CURVE_POINTS).map(|p| p as f64).collect();
        let panels = self.panels.len() as u32;
        let mut rest = plots;
        for (k, panel) in self.panels.iter().enumerate() {
            let last = k as u32 + 1 == panels;
            let height = CURVE_PLOT.1 + PLOT_MARGIN + if last { X_LABEL_AREA } else { 0 };
            let height = height.min(h.saturating_sub(TITLE_HEIGHT));
            let (area, below) = rest.split_vertically(height);
            rest = below;
            let top_value = (panel.each.iter().flatten())
                .chain(
                    panel
                        .mean
                        .iter()
                        .zip(&panel.sd)
                        .map(|(m, s)| m + s)
                        .collect::<Vec<_>>()
                        .iter(),
                )
                .filter(|v| v.is_finite())
                .fold(0.0f64, |m, &v| m.max(v));
            let y1 = if top_value > 0.0 {
                1.05 * top_value
            } else {
                1.0
            };
            let mut chart = ChartBuilder::on(&area)
                .margin(PLOT_MARGIN)
                .margin_top(0)
                .margin_bottom(if last { 0 } else { PLOT_MARGIN })
                .margin_right(PLOT_MARGIN + 24)
                .x_label_area_size(if last { X_LABEL_AREA } else { 0 })
                .y_label_area_size(Y_LABEL_AREA + 24)
                .build_cartesian_2d(0.0..100.0, 0.0..y1)
                .map_err(figure_error)?;
            let y_fmt = tick_formatter(y1, 4);
            let x_fmt = |v: &f64| format!("{v:.0}");
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(panel.label.as_str())
                .label_style((FONT, TICK_SIZE))
                .axis_desc_style((FONT, LABEL_SIZE * 0.8))
                .x_labels(11)
                .y_labels(4)
                .x_label_formatter(&x_fmt)
                .y_label_formatter(&y_fmt)
                .bold_line_style(COLOR_GRID.stroke_width(1))
                .light_line_style(TRANSPARENT.stroke_width(0))
                .axis_style(BLACK.stroke_width(1));
            if last {
                mesh.x_desc("stance (% of contact)");
            }
            mesh.draw().map_err(figure_error)?;
            if panel.each.is_empty() {
                continue;
            }
            if self.band {
                let upper = x
                    .iter()
                    .zip(&panel.mean)
                    .zip(&panel.sd)
                    .map(|((&x, m), s)| (x, m + s));
                let lower = (x.iter().zip(&panel.mean).zip(&panel.sd))
                    .map(|((&x, m), s)| (x, (m - s).max(0.0)))
                    .rev();
                let band: Vec<(f64, f64)> = upper.chain(lower).collect();
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        band,
                        COLOR_A.mix(0.18).filled(),
                    )))
                    .map_err(figure_error)?;
                for sign in [1.0, -1.0] {
                    let edge: Vec<(f64, f64)> = (x.iter().zip(&panel.mean).zip(&panel.sd))
                        .map(|((&x, m), s)| (x, (m + sign * s).max(0.0)))
                        .collect();
                    chart
                        .draw_series(std::iter::once(DashedPathElement::new(
                            edge,
                            6,
                            4,
                            COLOR_A.stroke_width(1),
                        )))
                        .map_err(figure_error)?;
                }
            }
            for c in &panel.each {
                let line: Vec<(f64, f64)> = x.iter().copied().zip(c.iter().copied()).collect();
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        line,
                        COLOR_STANCE.stroke_width(1),
                    )))
                    .map_err(figure_error)?;
            }
            let mean: Vec<(f64, f64)> = x.iter().copied().zip(panel.mean.iter().copied()).collect();
            chart
                .draw_series(std::iter::once(PathElement::new(
                    mean,
                    COLOR_A.stroke_width(3),
                )))
                .map_err(figure_error)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pedo_io::Recording;

    #[test]
    fn mean_and_sd_are_numpys() {
        // numpy: mean([1, 2, 6]) = 3, std(ddof=1) = sqrt(7).
        let (a, b, c) = ([1.0, 0.0], [2.0, 0.0], [6.0, 0.0]);
        let (mean, sd) = mean_and_sd(&[&a, &b, &c]);
        assert_eq!(mean, [3.0, 0.0]);
        assert!((sd[0] - 7f64.sqrt()).abs() < 1e-12);
        assert_eq!(sd[1], 0.0);
        let (mean, sd) = mean_and_sd(&[&a]);
        assert_eq!((mean, sd), (vec![1.0, 0.0], vec![0.0, 0.0]));
    }

    #[test]
    fn the_figure_draws_every_stance_and_says_how_many() {
        // Two steps of 20 frames in 60 frames of 2 × 2 sensels at 100 Hz, kPa.
        let n = 60;
        let mut data = vec![0.0f32; 4 * n];
        for t in (5..25).chain(35..55) {
            for v in &mut data[4 * t..4 * t + 4] {
                *v = 100.0 + t as f32;
            }
        }
        let rec = Recording::new(n, 2, 2, data, vec![true; 4])
            .unwrap()
            .with_pitch_mm([5.0, 5.0])
            .unwrap()
            .with_frame_rate(100.0)
            .unwrap()
            .with_units("kPa");
        let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
        assert_eq!(m.stances.len(), 2);
        let fig = StanceCurvesFigure { measures: &m };
        let svg = fig.to_svg().unwrap();
        assert!(
            svg.contains("2 stances; mean ± SD of the 2 complete"),
            "{svg}"
        );
        assert!(svg.contains("force (N)") && svg.contains("contact area (mm²)"));
        assert!(svg.contains("peak pressure (kPa)") && svg.contains("stance (% of contact)"));
        let png = fig.to_png().unwrap();
        assert_eq!(&png[1..4], b"PNG");
        // Without a stance the panels are drawn empty and the subtitle says why.
        let mut m0 = m.clone();
        m0.stances.clear();
        let svg = StanceCurvesFigure { measures: &m0 }.to_svg().unwrap();
        assert!(svg.contains("no stance among the frames"));
    }
}
