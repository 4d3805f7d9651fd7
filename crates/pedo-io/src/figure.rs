//! Figures a researcher can open: matches between two objects and node tracks, as SVG or PNG.
//!
//! A [`Figure`] records vector primitives in data coordinates (x = column, y = row, so y grows
//! downwards as in the pressure image) and renders them either to SVG text or to an anti-aliased
//! RGB raster encoded as PNG. Both renderings come from the same primitives, so they always agree.

use std::io::Cursor;

/// An RGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    pub const BLUE: Rgb = Rgb(31, 119, 180);
    pub const RED: Rgb = Rgb(214, 39, 40);
    pub const GREEN: Rgb = Rgb(44, 160, 44);
    pub const ORANGE: Rgb = Rgb(255, 127, 14);
    pub const GREY: Rgb = Rgb(150, 150, 150);

    fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }

    /// A colour from a cyclic qualitative palette, for the `k`-th track or object.
    pub fn palette(k: usize) -> Rgb {
        const P: [Rgb; 10] = [
            Rgb(31, 119, 180),
            Rgb(255, 127, 14),
            Rgb(44, 160, 44),
            Rgb(214, 39, 40),
            Rgb(148, 103, 189),
            Rgb(140, 86, 75),
            Rgb(227, 119, 194),
            Rgb(127, 127, 127),
            Rgb(188, 189, 34),
            Rgb(23, 190, 207),
        ];
        P[k % P.len()]
    }
}

#[derive(Debug, Clone)]
enum Primitive {
    Line {
        a: [f64; 2],
        b: [f64; 2],
        color: Rgb,
        width: f64,
        dashed: bool,
    },
    Polyline {
        points: Vec<[f64; 2]>,
        closed: bool,
        color: Rgb,
        width: f64,
    },
    Dot {
        at: [f64; 2],
        radius: f64,
        color: Rgb,
    },
    Text {
        at: [f64; 2],
        text: String,
        color: Rgb,
    },
    /// A grey-level image (values in [0, 1], NaN drawn as background) covering
    /// `[x0, x0 + cols·pitch] × [y0, y0 + rows·pitch]`.
    Image {
        values: Vec<f32>,
        rows: usize,
        cols: usize,
        origin: [f64; 2],
        pitch: f64,
    },
}

/// A figure in data coordinates, rendered to SVG or PNG with a fixed pixel scale.
#[derive(Debug, Clone)]
pub struct Figure {
    items: Vec<Primitive>,
    /// Pixels per data unit.
    scale: f64,
    margin: f64,
}

impl Figure {
    /// A new, empty figure; `scale` is the number of output pixels per data unit.
    pub fn new(scale: f64) -> Self {
        Self {
            items: Vec::new(),
            scale: scale.max(1e-6),
            margin: 12.0,
        }
    }

    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], color: Rgb, width: f64) -> &mut Self {
        self.items.push(Primitive::Line {
            a,
            b,
            color,
            width,
            dashed: false,
        });
        self
    }

    pub fn dashed_line(&mut self, a: [f64; 2], b: [f64; 2], color: Rgb, width: f64) -> &mut Self {
        self.items.push(Primitive::Line {
            a,
            b,
            color,
            width,
            dashed: true,
        });
        self
    }

    pub fn polyline(
        &mut self,
        points: &[[f64; 2]],
        closed: bool,
        color: Rgb,
        width: f64,
    ) -> &mut Self {
        self.items.push(Primitive::Polyline {
            points: points.to_vec(),
            closed,
            color,
            width,
        });
        self
    }

    pub fn dot(&mut self, at: [f64; 2], radius: f64, color: Rgb) -> &mut Self {
        self.items.push(Primitive::Dot { at, radius, color });
        self
    }

    /// A label; drawn in the SVG only (the PNG raster carries no font).
    pub fn text(&mut self, at: [f64; 2], text: impl Into<String>, color: Rgb) -> &mut Self {
        self.items.push(Primitive::Text {
            at,
            text: text.into(),
            color,
        });
        self
    }

    /// A grey-level background image, `values` row-major and scaled to [0, 1] by the caller.
    pub fn image(
        &mut self,
        values: &[f32],
        rows: usize,
        cols: usize,
        origin: [f64; 2],
        pitch: f64,
    ) -> &mut Self {
        if values.len() == rows * cols {
            self.items.push(Primitive::Image {
                values: values.to_vec(),
                rows,
                cols,
                origin,
                pitch,
            });
        }
        self
    }

    /// Bounding box `[xmin, ymin, xmax, ymax]` of everything drawn (a unit box when empty).
    fn bounds(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut add = |p: [f64; 2]| {
            if p[0].is_finite() && p[1].is_finite() {
                b[0] = b[0].min(p[0]);
                b[1] = b[1].min(p[1]);
                b[2] = b[2].max(p[0]);
                b[3] = b[3].max(p[1]);
            }
        };
        for item in &self.items {
            match item {
                Primitive::Line { a, b, .. } => {
                    add(*a);
                    add(*b);
                }
                Primitive::Polyline { points, .. } => points.iter().for_each(|&p| add(p)),
                Primitive::Dot { at, .. } | Primitive::Text { at, .. } => add(*at),
                Primitive::Image {
                    rows,
                    cols,
                    origin,
                    pitch,
                    ..
                } => {
                    add(*origin);
                    add([
                        origin[0] + *cols as f64 * pitch,
                        origin[1] + *rows as f64 * pitch,
                    ]);
                }
            }
        }
        if b[0] > b[2] {
            return [0.0, 0.0, 1.0, 1.0];
        }
        b
    }

    /// Output size in pixels and the data → pixel transform.
    fn layout(&self) -> (u32, u32, impl Fn([f64; 2]) -> [f64; 2]) {
        let [x0, y0, x1, y1] = self.bounds();
        let (s, m) = (self.scale, self.margin);
        let w = ((x1 - x0) * s + 2.0 * m).ceil().clamp(16.0, 8192.0) as u32;
        let h = ((y1 - y0) * s + 2.0 * m).ceil().clamp(16.0, 8192.0) as u32;
        (w, h, move |p: [f64; 2]| {
            [(p[0] - x0) * s + m, (p[1] - y0) * s + m]
        })
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let (w, h, tx) = self.layout();
        let mut out = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n\
             <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        );
        for item in &self.items {
            match item {
                Primitive::Line {
                    a,
                    b,
                    color,
                    width,
                    dashed,
                } => {
                    let (p, q) = (tx(*a), tx(*b));
                    let dash = if *dashed {
                        " stroke-dasharray=\"4 3\""
                    } else {
                        ""
                    };
                    out += &format!(
                        "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"{}\" stroke-width=\"{width}\"{dash}/>\n",
                        p[0], p[1], q[0], q[1], color.hex()
                    );
                }
                Primitive::Polyline {
                    points,
                    closed,
                    color,
                    width,
                } => {
                    let pts: Vec<String> = points
                        .iter()
                        .map(|&p| {
                            let q = tx(p);
                            format!("{:.2},{:.2}", q[0], q[1])
                        })
                        .collect();
                    let tag = if *closed { "polygon" } else { "polyline" };
                    out += &format!(
                        "<{tag} points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\"/>\n",
                        pts.join(" "),
                        color.hex()
                    );
                }
                Primitive::Dot { at, radius, color } => {
                    let p = tx(*at);
                    out += &format!(
                        "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"{radius}\" fill=\"{}\"/>\n",
                        p[0],
                        p[1],
                        color.hex()
                    );
                }
                Primitive::Text { at, text, color } => {
                    let p = tx(*at);
                    out += &format!(
                        "<text x=\"{:.2}\" y=\"{:.2}\" font-family=\"sans-serif\" font-size=\"12\" fill=\"{}\">{}</text>\n",
                        p[0],
                        p[1],
                        color.hex(),
                        xml_escape(text)
                    );
                }
                Primitive::Image {
                    values,
                    rows,
                    cols,
                    origin,
                    pitch,
                } => {
                    for r in 0..*rows {
                        for c in 0..*cols {
                            let v = values[r * cols + c];
                            if !v.is_finite() {
                                continue;
                            }
                            let g = grey(v);
                            let p =
                                tx([origin[0] + c as f64 * pitch, origin[1] + r as f64 * pitch]);
                            let s = pitch * self.scale;
                            out += &format!(
                                "<rect x=\"{:.2}\" y=\"{:.2}\" width=\"{s:.2}\" height=\"{s:.2}\" fill=\"{}\"/>\n",
                                p[0],
                                p[1],
                                Rgb(g, g, g).hex()
                            );
                        }
                    }
                }
            }
        }
        out += "</svg>\n";
        out
    }

    /// The figure rasterised (anti-aliased) and encoded as PNG bytes.
    pub fn to_png(&self) -> Vec<u8> {
        let (w, h, tx) = self.layout();
        let mut canvas = Canvas::new(w, h);
        for item in &self.items {
            match item {
                Primitive::Line {
                    a,
                    b,
                    color,
                    width,
                    dashed,
                } => {
                    let (p, q) = (tx(*a), tx(*b));
                    if *dashed {
                        canvas.dashed(p, q, *color, *width);
                    } else {
                        canvas.segment(p, q, *color, *width);
                    }
                }
                Primitive::Polyline {
                    points,
                    closed,
                    color,
                    width,
                } => {
                    let pts: Vec<[f64; 2]> = points.iter().map(|&p| tx(p)).collect();
                    for win in pts.windows(2) {
                        canvas.segment(win[0], win[1], *color, *width);
                    }
                    if *closed && pts.len() > 2 {
                        canvas.segment(pts[pts.len() - 1], pts[0], *color, *width);
                    }
                }
                Primitive::Dot { at, radius, color } => canvas.disc(tx(*at), *radius, *color),
                Primitive::Text { .. } => {}
                Primitive::Image {
                    values,
                    rows,
                    cols,
                    origin,
                    pitch,
                } => {
                    for r in 0..*rows {
                        for c in 0..*cols {
                            let v = values[r * cols + c];
                            if v.is_finite() {
                                let g = grey(v);
                                let p = tx([
                                    origin[0] + c as f64 * pitch,
                                    origin[1] + r as f64 * pitch,
                                ]);
                                let q = tx([
                                    origin[0] + (c + 1) as f64 * pitch,
                                    origin[1] + (r + 1) as f64 * pitch,
                                ]);
                                canvas.rect(p, q, Rgb(g, g, g));
                            }
                        }
                    }
                }
            }
        }
        canvas.encode_png()
    }
}

/// Light-to-dark grey ramp so that drawn lines stay visible on top of high pressure.
fn grey(v: f32) -> u8 {
    (250.0 - 150.0 * v.clamp(0.0, 1.0)) as u8
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A white RGB raster with coverage-based anti-aliasing.
struct Canvas {
    w: u32,
    h: u32,
    px: Vec<[f32; 3]>,
}

impl Canvas {
    fn new(w: u32, h: u32) -> Self {
        Self {
            w,
            h,
            px: vec![[1.0; 3]; (w * h) as usize],
        }
    }

    fn blend(&mut self, x: i64, y: i64, color: Rgb, alpha: f64) {
        if x < 0 || y < 0 || x >= self.w as i64 || y >= self.h as i64 || alpha <= 0.0 {
            return;
        }
        let a = alpha.min(1.0) as f32;
        let p = &mut self.px[(y as u32 * self.w + x as u32) as usize];
        let c = [color.0, color.1, color.2];
        for k in 0..3 {
            p[k] = p[k] * (1.0 - a) + (c[k] as f32 / 255.0) * a;
        }
    }

    /// A thick segment: every pixel within `width/2` of the segment, with a 1-pixel soft edge.
    fn segment(&mut self, p: [f64; 2], q: [f64; 2], color: Rgb, width: f64) {
        // Long diagonal segments have large bounding boxes: cover them piecewise so the work
        // stays proportional to the length. Pieces share end points; blending twice there is
        // invisible at these widths.
        let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        if len > 16.0 {
            let pieces = (len / 8.0).ceil() as usize;
            let at = |t: f64| [p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t];
            for k in 0..pieces {
                self.segment_piece(
                    at(k as f64 / pieces as f64),
                    at((k + 1) as f64 / pieces as f64),
                    color,
                    width,
                );
            }
        } else {
            self.segment_piece(p, q, color, width);
        }
    }

    fn segment_piece(&mut self, p: [f64; 2], q: [f64; 2], color: Rgb, width: f64) {
        let half = (width * 0.5).max(0.5);
        let (x0, x1) = (p[0].min(q[0]) - half - 1.0, p[0].max(q[0]) + half + 1.0);
        let (y0, y1) = (p[1].min(q[1]) - half - 1.0, p[1].max(q[1]) + half + 1.0);
        let d = [q[0] - p[0], q[1] - p[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        for y in y0.floor() as i64..=y1.ceil() as i64 {
            for x in x0.floor() as i64..=x1.ceil() as i64 {
                let c = [x as f64 + 0.5, y as f64 + 0.5];
                let t = if len2 > 0.0 {
                    (((c[0] - p[0]) * d[0] + (c[1] - p[1]) * d[1]) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let e = [p[0] + t * d[0] - c[0], p[1] + t * d[1] - c[1]];
                let dist = (e[0] * e[0] + e[1] * e[1]).sqrt();
                self.blend(x, y, color, half + 0.5 - dist);
            }
        }
    }

    fn dashed(&mut self, p: [f64; 2], q: [f64; 2], color: Rgb, width: f64) {
        let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        let (on, period) = (4.0, 7.0);
        let mut s = 0.0;
        while s < len {
            let e = (s + on).min(len);
            let at = |t: f64| {
                [
                    p[0] + (q[0] - p[0]) * t / len,
                    p[1] + (q[1] - p[1]) * t / len,
                ]
            };
            self.segment(at(s), at(e), color, width);
            s += period;
        }
    }

    fn disc(&mut self, c: [f64; 2], r: f64, color: Rgb) {
        for y in (c[1] - r - 1.0).floor() as i64..=(c[1] + r + 1.0).ceil() as i64 {
            for x in (c[0] - r - 1.0).floor() as i64..=(c[0] + r + 1.0).ceil() as i64 {
                let d = ((x as f64 + 0.5 - c[0]).powi(2) + (y as f64 + 0.5 - c[1]).powi(2)).sqrt();
                self.blend(x, y, color, r + 0.5 - d);
            }
        }
    }

    fn rect(&mut self, p: [f64; 2], q: [f64; 2], color: Rgb) {
        for y in p[1].round() as i64..q[1].round() as i64 {
            for x in p[0].round() as i64..q[0].round() as i64 {
                self.blend(x, y, color, 1.0);
            }
        }
    }

    fn encode_png(&self) -> Vec<u8> {
        let bytes: Vec<u8> = self
            .px
            .iter()
            .flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect();
        let img = image::RgbImage::from_raw(self.w, self.h, bytes).expect("buffer sized w*h*3");
        let mut out = Vec::new();
        // Fast compression: figures are written by the hundred and stay small anyway.
        let encoder = image::codecs::png::PngEncoder::new_with_quality(
            Cursor::new(&mut out),
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Adaptive,
        );
        img.write_with_encoder(encoder)
            .expect("PNG encoding into memory does not fail");
        out
    }
}

/// Pixels per data unit that make the larger side of `shapes` about `target` pixels.
fn fit_scale(shapes: &[&modal_core::Shape], dims: [usize; 2], target: f64) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for s in shapes {
        for i in 0..s.len() {
            let p = s.point(i);
            for k in 0..2 {
                lo[k] = lo[k].min(p[dims[k]]);
                hi[k] = hi[k].max(p[dims[k]]);
            }
        }
    }
    let range = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if range.is_finite() && range > 0.0 {
        target / range
    } else {
        1.0
    }
}

/// The projection of a shape on coordinates `dims`, shifted by `offset`. Screen y grows
/// downwards, which suits image rows; a z (height) axis is flipped so that pressure points up.
fn project(s: &modal_core::Shape, dims: [usize; 2], offset: [f64; 2]) -> Vec<[f64; 2]> {
    let flip = if dims[1] == 2 { -1.0 } else { 1.0 };
    (0..s.len())
        .map(|i| {
            let p = s.point(i);
            [p[dims[0]] + offset[0], flip * p[dims[1]] + offset[1]]
        })
        .collect()
}

/// Two objects and their correspondences: the first object in blue, the second in red, a grey
/// line per one-to-one match and a dashed orange line per excess match. 3-D objects are shown in
/// two views side by side, from above (x, y) and from the side (x, z).
pub fn match_figure(
    a: &modal_core::Shape,
    b: &modal_core::Shape,
    pairs: &[modal_core::MatchPair],
) -> Figure {
    let views: Vec<[usize; 2]> = if a.dim() == 3 && b.dim() == 3 {
        vec![[0, 1], [0, 2]]
    } else {
        vec![[0, 1]]
    };
    let scale = fit_scale(&[a, b], [0, 1], 560.0);
    let mut fig = Figure::new(scale);
    let mut x_offset = 0.0;
    for dims in views {
        let pa = project(a, dims, [x_offset, 0.0]);
        let pb = project(b, dims, [x_offset, 0.0]);
        let closed =
            |s: &modal_core::Shape| matches!(s.topology(), modal_core::Topology::ClosedContour);
        if closed(a) && dims == [0, 1] {
            fig.polyline(&pa, true, Rgb::BLUE, 1.0);
        }
        if closed(b) && dims == [0, 1] {
            fig.polyline(&pb, true, Rgb::RED, 1.0);
        }
        for m in pairs {
            if m.a < pa.len() && m.b < pb.len() {
                if m.excess {
                    fig.dashed_line(pa[m.a], pb[m.b], Rgb::ORANGE, 1.0);
                } else {
                    fig.line(pa[m.a], pb[m.b], Rgb::GREY, 1.0);
                }
            }
        }
        pa.iter().for_each(|&p| {
            fig.dot(p, 2.5, Rgb::BLUE);
        });
        pb.iter().for_each(|&p| {
            fig.dot(p, 2.0, Rgb::RED);
        });
        let width = pa
            .iter()
            .chain(&pb)
            .map(|p| p[0])
            .fold(f64::NEG_INFINITY, f64::max)
            - pa.iter()
                .chain(&pb)
                .map(|p| p[0])
                .fold(f64::INFINITY, f64::min);
        x_offset += width + 40.0 / scale;
    }
    fig
}

/// Node tracks over the recording's peak-pressure image: one coloured polyline per track, with a
/// dot where it starts, for the `max_tracks` longest tracks spanning at least `min_steps` objects
/// (thousands of overlapping tracks would hide each other). 2-D coordinates in sensels.
pub fn tracks_figure(
    r: &crate::sequence::SequenceResult,
    peak: &crate::Grid,
    min_steps: usize,
    max_tracks: usize,
) -> Figure {
    let mut fig = Figure::new(14.0);
    let max = peak.max();
    if max > 0.0 {
        // Square-root scaling keeps the low-pressure outline of the foot visible.
        let values: Vec<f32> = peak
            .data()
            .iter()
            .map(|&v| (v.max(0.0) / max).sqrt() as f32)
            .collect();
        fig.image(&values, peak.rows(), peak.cols(), [-0.5, -0.5], 1.0);
    }
    let mut chosen: Vec<&crate::sequence::Track> = r
        .tracks
        .iter()
        .filter(|t| t.steps.len() >= min_steps.max(2))
        .collect();
    // Longest first; ties by first object so the choice is deterministic.
    chosen.sort_by_key(|t| (std::cmp::Reverse(t.steps.len()), t.steps[0]));
    chosen.truncate(max_tracks);
    for (k, t) in chosen.iter().enumerate() {
        let pts: Vec<[f64; 2]> = t
            .steps
            .iter()
            .map(|&(o, n)| {
                let p = r.objects[o].shape.point(n);
                [p[0], p[1]]
            })
            .collect();
        let c = Rgb::palette(k);
        fig.polyline(&pts, false, c, 1.0);
        fig.dot(pts[0], 2.0, c);
    }
    fig
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_and_png_render_the_same_primitives() {
        let mut f = Figure::new(10.0);
        f.polyline(&[[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]], true, Rgb::BLUE, 1.5)
            .line([0.0, 0.0], [4.0, 3.0], Rgb::GREY, 1.0)
            .dot([4.0, 3.0], 2.0, Rgb::RED)
            .text([0.0, 3.0], "a < b", Rgb::BLACK);
        let svg = f.to_svg();
        assert!(svg.starts_with("<svg") && svg.contains("<polygon") && svg.contains("a &lt; b"));
        let png = f.to_png();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        // 4 × 3 data units at 10 px each plus a 12 px margin on every side.
        assert_eq!((img.width(), img.height()), (64, 54));
        // The red dot is drawn at (4, 3) → pixel (52, 42); the top-left corner stays white.
        assert_eq!(img.get_pixel(52, 42).0, [214, 39, 40]);
        assert_eq!(img.get_pixel(0, 0).0, [255, 255, 255]);
    }
}
