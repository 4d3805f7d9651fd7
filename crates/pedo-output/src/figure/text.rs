//! Text for the bitmap figures, laid out with the bundled font.
//!
//! plotters' `ab_glyph` text path advances each glyph correctly but places its outline without
//! the glyph's left side bearing, so letters are spaced unevenly ("con tour"). [`TextBitmap`]
//! wraps the bitmap backend and lays text out itself: kerned advances, outlines at their true
//! bearings, sized like the SVG backend's text (an em of `size / 1.24` pixels) so that both
//! renderings of a figure have the same layout.

use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};

/// The bitmap backend with its text drawn by [`ab_glyph`] directly.
pub(super) struct TextBitmap<'a> {
    pub inner: BitMapBackend<'a>,
    pub font: FontRef<'static>,
}

type BitmapError<'a> = <BitMapBackend<'a> as DrawingBackend>::ErrorType;

impl TextBitmap<'_> {
    fn scale(&self, size: f64) -> PxScale {
        scale(&self.font, size)
    }

    /// Glyphs of `text` positioned along the baseline from x = 0, and the total advance.
    fn layout(&self, text: &str, size: f64) -> (Vec<ab_glyph::Glyph>, f32) {
        layout(&self.font, text, size)
    }
}

/// The pixel scale for plotters' font `size`, matching the SVG backend's `font-size`.
fn scale(font: &FontRef<'_>, size: f64) -> PxScale {
    let em = size / 1.24;
    let height = font.height_unscaled() as f64;
    let per_em = font.units_per_em().unwrap_or(2048.0) as f64;
    PxScale::from((em * height / per_em) as f32)
}

fn layout(font: &FontRef<'_>, text: &str, size: f64) -> (Vec<ab_glyph::Glyph>, f32) {
    let font = font.as_scaled(scale(font, size));
    let mut glyphs = Vec::with_capacity(text.len());
    let (mut x, mut prev) = (0.0f32, None);
    for c in text.chars() {
        let id = font.glyph_id(c);
        if let Some(p) = prev {
            x += font.kern(p, id);
        }
        glyphs.push(id.with_scale_and_position(font.scale(), point(x, 0.0)));
        x += font.h_advance(id);
        prev = Some(id);
    }
    (glyphs, x)
}

/// The width in pixels of `text` at plotters' font `size` in `font`, as both backends lay it
/// out: what the figure's layout reserves for it, so that no text is cut at an edge.
pub(super) fn text_width(font: &FontRef<'_>, text: &str, size: f64) -> u32 {
    layout(font, text, size).1.ceil() as u32
}

impl<'a> DrawingBackend for TextBitmap<'a> {
    type ErrorType = BitmapError<'a>;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_pixel(point, color)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.fill_polygon(vert, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<TStyle: BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let (_, width) = self.layout(text, style.size());
        let font = self.font.as_scaled(self.scale(style.size()));
        Ok((
            width.ceil() as u32,
            (font.ascent() - font.descent()).ceil() as u32,
        ))
    }

    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let (glyphs, width) = self.layout(text, style.size());
        let font = self.font.as_scaled(self.scale(style.size()));
        let anchor = style.anchor();
        let dx = match anchor.h_pos {
            HPos::Left => 0.0,
            HPos::Center => -0.5 * width,
            HPos::Right => -width,
        };
        // Baseline offset from the anchor (ascent above the baseline, descent below it).
        let dy = match anchor.v_pos {
            VPos::Top => font.ascent(),
            VPos::Center => 0.5 * (font.ascent() + font.descent()),
            VPos::Bottom => font.descent(),
        };
        let transform = style.transform();
        let mut coverage = Vec::new();
        for glyph in glyphs {
            if let Some(outline) = font.outline_glyph(glyph) {
                let bounds = outline.px_bounds();
                outline.draw(|gx, gy, c| {
                    let x = (bounds.min.x + gx as f32 + dx).round() as i32;
                    let y = (bounds.min.y + gy as f32 + dy).round() as i32;
                    coverage.push((transform.transform(x, y), c));
                });
            }
        }
        for ((x, y), c) in coverage {
            if c > 0.0 {
                let pixel = BackendColor {
                    alpha: color.alpha * c.min(1.0) as f64,
                    rgb: color.rgb,
                };
                self.inner.draw_pixel((pos.0 + x, pos.1 + y), pixel)?;
            }
        }
        Ok(())
    }
}
