//! The figure of a registered stack (`pedomatch register`): the template, the mean and the
//! standard deviation of the registered peak images side by side, each on the template's grid
//! with its axes and colour bar.

use super::measure_figures::format_value;
use super::*;

/// The registered stack's figure: three panels of one grid (`rows × cols`, row-major).
#[derive(Debug, Clone)]
pub struct RegisteredStackFigure<'a> {
    /// Rows of the template's grid.
    pub rows: usize,
    /// Columns of the template's grid.
    pub cols: usize,
    /// The template's peak image.
    pub template: &'a [f64],
    /// The mean of the registered peak images.
    pub mean: &'a [f64],
    /// Their standard deviation.
    pub sd: &'a [f64],
    /// How many trials the stack holds.
    pub trials: usize,
    /// The grid's scale and the pressure unit.
    pub axes: &'a FigureAxes,
}

impl RegisteredStackFigure<'_> {
    /// The three panels side by side as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        use image::ImageEncoder;
        let unit = if self.axes.pressure_units.is_empty() {
            "file units".to_string()
        } else {
            self.axes.pressure_units.clone()
        };
        let n = pedo_io::counted(self.trials, "trial");
        let panels = [
            (
                self.template,
                "Template".to_string(),
                "template peak pressure",
            ),
            (
                self.mean,
                format!("Mean of {n}"),
                "mean registered peak pressure",
            ),
            (
                self.sd,
                format!("SD of {n}"),
                "SD of registered peak pressure",
            ),
        ];
        let mut rendered = Vec::new();
        for (values, title, what) in panels {
            let layout = self.panel(values, title, &format!("{what} ({unit})"))?;
            rendered.push(render_rgb(&layout)?);
        }
        let h = rendered.iter().map(|r| r.1).max().unwrap_or(0);
        let w: u32 = rendered.iter().map(|r| r.0).sum();
        let mut pixels = vec![255u8; w as usize * h as usize * 3];
        let mut x0 = 0usize;
        for (pw, ph, px) in &rendered {
            for row in 0..*ph as usize {
                let src = &px[row * *pw as usize * 3..(row + 1) * *pw as usize * 3];
                let at = (row * w as usize + x0) * 3;
                pixels[at..at + src.len()].copy_from_slice(src);
            }
            x0 += *pw as usize;
        }
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Adaptive,
        )
        .write_image(&pixels, w, h, image::ExtendedColorType::Rgb8)
        .map_err(figure_error)?;
        Ok(out)
    }

    fn panel(&self, values: &[f64], title: String, label: &str) -> Result<Layout> {
        let (rows, cols) = (self.rows, self.cols);
        if values.len() != rows * cols {
            return Err(IoError::invalid(
                "a registered image does not fill the template's grid",
            ));
        }
        let corner = |c: f64, r: f64| self.axes.to_plot([c, r]);
        let mut bounds = Bounds::of([
            corner(-0.5, -0.5),
            corner(cols as f64 - 0.5, rows as f64 - 0.5),
        ])
        .ok_or_else(|| IoError::invalid("the template's grid has no finite extent"))?;
        bounds.pad = false;
        let top = values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let cells: Vec<([(f64, f64); 2], f64)> = (0..rows * cols)
            .filter(|&i| values[i].is_finite() && values[i] > 0.0)
            .map(|i| {
                let (row, col) = ((i / cols) as f64, (i % cols) as f64);
                let (x0, y0) = corner(col - 0.5, row - 0.5);
                let (x1, y1) = corner(col + 0.5, row + 0.5);
                ([(x0, y0), (x1, y1)], values[i])
            })
            .collect();
        let image = (top > 0.0).then(|| PressureImage {
            cells,
            max: top,
            label: label.to_string(),
            marks: Vec::new(),
        });
        let subtitle = format!("maximum {}", format_value(top));
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
