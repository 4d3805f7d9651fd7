//! The recording played back as an animated GIF: each frame's pressure image with its contours
//! and its matches into the next frame, drawn like the static figures (same axes, colour bar,
//! legend and font).

use super::*;
use image::RgbaImage;
use pedo_io::Recording;

/// Most frames an animation holds: a longer run keeps every `s`-th frame, `s` the smallest step
/// that fits, and each shown frame lasts `s` frame intervals, so the playback keeps real time.
/// About 2 s of a typical 50–100 Hz plate recording per 100 frames, and a few MB at most.
pub const MAX_ANIMATION_FRAMES: usize = 150;

/// GIF delays are whole hundredths of a second and browsers show delays under 2 cs as 10 cs:
/// the shortest delay written. A faster recording shows every `s`-th frame, `s` the smallest
/// step whose frames last this long, so that it still plays in real time.
pub const MIN_GIF_DELAY_CS: u32 = 2;

/// Delay of each shown frame when the recording has no frame rate: 10 frames per second.
pub const DEFAULT_GIF_DELAY_CS: u32 = 10;

/// An animation of frames `frames.0..frames.1` of a run: per frame the pressure image (grey,
/// on the recording's peak scale), the outlines (or nodes) of its objects, and the matches of
/// each pair leaving the frame as segments onto the next frame's objects, excess matches dashed.
#[derive(Debug, Clone)]
pub struct Animation<'a> {
    /// The recording whose frames are played.
    pub recording: &'a Recording,
    /// The run on it: its objects and pairs are drawn over the frames.
    pub result: &'a SequenceResult,
    /// Units, timing and pressure units of the recording ([`FigureAxes::of_recording`]).
    pub axes: &'a FigureAxes,
    /// Frames `start..end` (0-based, end excluded) to play.
    pub frames: (usize, usize),
}

impl Animation<'_> {
    /// Every how many frames one is shown: 1, or more for a run longer than
    /// [`MAX_ANIMATION_FRAMES`] frames or a recording faster than [`MIN_GIF_DELAY_CS`] allows
    /// (a 100 Hz recording shows every second frame, each 2 cs).
    pub fn frame_step(&self) -> usize {
        let n = self.frames.1.saturating_sub(self.frames.0);
        let for_length = n.div_ceil(MAX_ANIMATION_FRAMES);
        let for_speed = match self.axes.dt_s.filter(|dt| dt.is_finite() && *dt > 0.0) {
            // The tolerance keeps 100 Hz (0.01 s, not exactly representable) at a step of 2.
            Some(dt) => (f64::from(MIN_GIF_DELAY_CS) / (100.0 * dt) - 1e-9).ceil() as usize,
            None => 1,
        };
        for_length.max(for_speed).max(1)
    }

    /// The recording frames the animation shows, in order.
    pub fn shown_frames(&self) -> Vec<usize> {
        (self.frames.0..self.frames.1)
            .step_by(self.frame_step())
            .collect()
    }

    /// The delay of each shown frame in hundredths of a second: the frame step times the
    /// recording's frame interval, at least [`MIN_GIF_DELAY_CS`];
    /// [`DEFAULT_GIF_DELAY_CS`] times the step without a frame rate.
    pub fn delay_cs(&self) -> u32 {
        let step = self.frame_step() as f64;
        let cs = match self.axes.dt_s.filter(|dt| dt.is_finite() && *dt > 0.0) {
            Some(dt) => (step * dt * 100.0).round(),
            None => step * f64::from(DEFAULT_GIF_DELAY_CS),
        };
        (cs.min(f64::from(u16::MAX)) as u32).max(MIN_GIF_DELAY_CS)
    }

    /// The animation as GIF bytes, looping forever. Each frame after the first stores only
    /// the rectangle that changed, placed at its offset over the frames before it (which are
    /// kept, not cleared), so the file stays small and every frame shows the whole figure.
    pub fn to_gif(&self) -> Result<Vec<u8>> {
        let shown = self.shown_frames();
        if shown.is_empty() || self.frames.1 > self.recording.n_frames() {
            return Err(IoError::invalid(format!(
                "an animation needs frames within the recording's 0..{}, got {}..{}",
                self.recording.n_frames(),
                self.frames.0,
                self.frames.1
            )));
        }
        let peak = self.recording.peak_image().max();
        let delay = u16::try_from(self.delay_cs()).unwrap_or(u16::MAX);
        let render = |t: usize| -> Result<RgbaImage> {
            let (w, h, rgb) = render_rgb(&self.layout(t, peak)?)?;
            Ok(RgbaImage::from_fn(w, h, |x, y| {
                let i = 3 * (y as usize * w as usize + x as usize);
                image::Rgba([rgb[i], rgb[i + 1], rgb[i + 2], 255])
            }))
        };
        let first = render(shown[0])?;
        let mut out = Vec::new();
        {
            let (w, h) = (gif_size(first.width())?, gif_size(first.height())?);
            let mut encoder = gif::Encoder::new(&mut out, w, h, &[]).map_err(figure_error)?;
            encoder
                .set_repeat(gif::Repeat::Infinite)
                .map_err(figure_error)?;
            write_gif_frame(&mut encoder, 0, 0, first.clone(), delay)?;
            let mut previous = first;
            for &t in &shown[1..] {
                let image = render(t)?;
                let (x0, y0, part) = changed_part(&previous, &image);
                write_gif_frame(&mut encoder, x0, y0, part, delay)?;
                previous = image;
            }
        }
        Ok(out)
    }

    fn layout(&self, t: usize, peak: f64) -> Result<Layout> {
        let r = self.result;
        let plot = |s: &Shape, i: usize| {
            let p = s.point(i);
            self.axes.to_plot([p[0], p[1]])
        };
        let mut layers = Vec::new();
        let mut outlines = |s: &Shape, color| {
            let pts: Vec<(f64, f64)> = (0..s.len()).map(|i| plot(s, i)).collect();
            if matches!(s.topology(), Topology::ClosedContour) && pts.len() > 2 {
                let mut ring = pts.clone();
                ring.push(pts[0]);
                layers.push(Layer::Line {
                    points: ring,
                    color,
                    width: 2,
                });
            } else {
                layers.push(Layer::Dots {
                    points: pts,
                    color,
                    radius: 2,
                });
            }
        };
        let leaving: Vec<&pedo_track::PairMatch> = r
            .pairs
            .iter()
            .filter(|p| r.objects[p.a].frame == t)
            .collect();
        for o in r.objects.iter().filter(|o| o.frame == t) {
            outlines(&o.shape, COLOR_A);
        }
        for p in &leaving {
            if r.objects[p.b].frame != t {
                outlines(&r.objects[p.b].shape, COLOR_B);
            }
        }
        let (mut matched, mut excess) = (0, 0);
        for p in &leaving {
            let (sa, sb) = (&r.objects[p.a].shape, &r.objects[p.b].shape);
            for m in &p.result.pairs {
                let points = vec![plot(sa, m.a), plot(sb, m.b)];
                if m.excess {
                    excess += 1;
                    layers.push(Layer::Dashed {
                        points,
                        color: COLOR_EXCESS,
                    });
                } else {
                    matched += 1;
                    layers.push(Layer::Line {
                        points,
                        color: COLOR_MATCH,
                        width: 1,
                    });
                }
            }
        }
        // The matches first, the outlines over them.
        let outlines_drawn = layers.len() - matched - excess;
        layers.rotate_left(outlines_drawn);

        let grid = self.recording.frame(t)?;
        let (rows, cols) = (grid.rows(), grid.cols());
        let corner = |c: f64, r: f64| self.axes.to_plot([c, r]);
        let mut bounds = Bounds::of([
            corner(-0.5, -0.5),
            corner(cols as f64 - 0.5, rows as f64 - 0.5),
        ])
        .ok_or_else(|| IoError::invalid("the recording has no finite extent"))?;
        bounds.pad = false;
        let max = if peak.is_finite() && peak > 0.0 {
            peak
        } else {
            1.0
        };
        let image =
            PressureImage::of_grid(&grid, corner, max, self.axes.pressure_label("pressure"));
        let title = self.axes.frame_text(t);
        let objects = r.objects.iter().filter(|o| o.frame == t).count();
        let subtitle = format!(
            "{objects} object{}; {matched} matches ({excess} excess) into the next",
            if objects == 1 { "" } else { "s" }
        );
        let legend = vec![
            LegendEntry {
                text: "this frame".to_string(),
                glyph: Glyph::LineDot(COLOR_A),
            },
            LegendEntry {
                text: "matched onto".to_string(),
                glyph: Glyph::LineDot(COLOR_B),
            },
            LegendEntry {
                text: "match".to_string(),
                glyph: Glyph::Line(COLOR_MATCH),
            },
            LegendEntry {
                text: "excess match".to_string(),
                glyph: Glyph::Dashed(COLOR_EXCESS),
            },
        ];
        let mut layout = Layout::new(
            bounds,
            self.axes,
            title,
            subtitle,
            legend,
            Some(image),
            layers,
        );
        // Every frame of the GIF has the first one's size; its title, shorter than the plot
        // and legend anyway, must not change it.
        layout.fit_title = false;
        Ok(layout)
    }
}

/// The smallest rectangle of `next` that differs from `prev` (same size), with its top-left
/// corner; one pixel when nothing changed.
fn changed_part(prev: &RgbaImage, next: &RgbaImage) -> (u32, u32, RgbaImage) {
    let (w, h) = next.dimensions();
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (x, y, p) in next.enumerate_pixels() {
        if prev.get_pixel(x, y) != p {
            (x0, y0) = (x0.min(x), y0.min(y));
            (x1, y1) = (x1.max(x + 1), y1.max(y + 1));
        }
    }
    if x0 >= x1 {
        (x0, y0, x1, y1) = (0, 0, 1, 1);
    }
    let part = image::imageops::crop_imm(next, x0, y0, x1 - x0, y1 - y0).to_image();
    (x0, y0, part)
}

/// Writes `part` at `(left, top)` over the frames before it, which stay (disposal "keep").
fn write_gif_frame(
    encoder: &mut gif::Encoder<&mut Vec<u8>>,
    left: u32,
    top: u32,
    part: RgbaImage,
    delay_cs: u16,
) -> Result<()> {
    let (w, h) = (gif_size(part.width())?, gif_size(part.height())?);
    let mut rgba = part.into_raw();
    // Speed 30: the fastest colour quantisation; the figures hold few colours.
    let mut frame = gif::Frame::from_rgba_speed(w, h, &mut rgba, 30);
    frame.left = gif_size(left)?;
    frame.top = gif_size(top)?;
    frame.delay = delay_cs;
    frame.dispose = gif::DisposalMethod::Keep;
    encoder.write_frame(&frame).map_err(figure_error)
}

/// A GIF dimension or offset (16 bits).
fn gif_size(v: u32) -> Result<u16> {
    u16::try_from(v).map_err(|_| IoError::Figure(format!("{v} pixels is too large for a GIF")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::AnimationDecoder;
    use pedo_track::{run_sequence, SequenceOptions};

    /// A disc of pressure moving one sensel right per frame.
    fn moving_disc(frames: usize, rows: usize, cols: usize) -> Recording {
        let mut data = vec![0.0f32; frames * rows * cols];
        for t in 0..frames {
            for r in 0..rows {
                for c in 0..cols {
                    let (dy, dx) = (r as f64 - 8.0, c as f64 - 6.0 - (t % 8) as f64);
                    let d2 = dx * dx + dy * dy;
                    if d2 < 20.0 {
                        data[(t * rows + r) * cols + c] = (100.0 - 4.0 * d2) as f32;
                    }
                }
            }
        }
        Recording::from_array(frames, rows, cols, data, None).unwrap()
    }

    fn decode(gif: &[u8]) -> Vec<image::Frame> {
        image::codecs::gif::GifDecoder::new(std::io::Cursor::new(gif))
            .unwrap()
            .into_frames()
            .collect_frames()
            .unwrap()
    }

    #[test]
    fn every_frame_is_drawn_with_its_contours_and_matches_at_the_frame_rate() {
        let rec = moving_disc(5, 16, 24)
            .with_pitch_mm([5.0, 5.0])
            .unwrap()
            .with_frame_rate(25.0)
            .unwrap()
            .with_units("kPa");
        let result = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
        assert_eq!(result.pairs.len(), 4);
        let axes = FigureAxes::of_recording(&rec);
        let animation = Animation {
            recording: &rec,
            result: &result,
            axes: &axes,
            frames: (0, 5),
        };
        assert_eq!(animation.delay_cs(), 4);
        let frames = decode(&animation.to_gif().unwrap());
        assert_eq!(frames.len(), 5);
        let (w, h) = animation.layout(0, 100.0).unwrap().size();
        for f in &frames {
            assert_eq!(f.delay().numer_denom_ms(), (40, 1));
            assert_eq!(f.buffer().dimensions(), (w, h));
        }
        // Frames 0-3 show the matches into the next frame (contours of both frames drawn in
        // their colours); the last frame has no pair leaving it.
        let near = |p: &image::Rgba<u8>, c: RGBColor| {
            (0..3).all(|k| (i32::from(p.0[k]) - i32::from([c.0, c.1, c.2][k])).abs() <= 40)
        };
        let count = |f: &image::Frame, c| f.buffer().pixels().filter(|p| near(p, c)).count();
        // (The legend shows both colours too, equally in every frame.)
        let last_b = count(&frames[4], COLOR_B);
        for f in &frames[..4] {
            assert!(count(f, COLOR_B) > last_b + 30);
        }
        assert!(count(&frames[4], COLOR_A) > last_b + 30);
        assert_ne!(frames[0].buffer(), frames[1].buffer());
        // Every decoded frame is the whole figure of its recording frame (up to the GIF's
        // 256-colour quantisation), although frames 1-4 store only what changed.
        let peak = rec.peak_image().max();
        for (t, f) in frames.iter().enumerate() {
            let (w, h, rgb) = render_rgb(&animation.layout(t, peak).unwrap()).unwrap();
            assert_eq!(f.buffer().dimensions(), (w, h));
            let far = f
                .buffer()
                .pixels()
                .zip(rgb.chunks_exact(3))
                .filter(|(p, q)| (0..3).any(|k| p.0[k].abs_diff(q[k]) > 48) || p.0[3] != 255)
                .count();
            assert!(
                far * 200 < (w * h) as usize,
                "frame {t}: {far} of {} pixels differ from the figure",
                w * h
            );
        }
    }

    #[test]
    fn a_frame_that_changes_a_corner_stores_that_corner_at_its_offset() {
        let prev = RgbaImage::from_pixel(20, 10, image::Rgba([1, 2, 3, 255]));
        let mut next = prev.clone();
        next.put_pixel(15, 7, image::Rgba([200, 0, 0, 255]));
        next.put_pixel(12, 4, image::Rgba([0, 200, 0, 255]));
        let (x0, y0, part) = changed_part(&prev, &next);
        assert_eq!((x0, y0, part.dimensions()), (12, 4, (4, 4)));
        assert_eq!(part.get_pixel(3, 3), next.get_pixel(15, 7));
        let (x0, y0, part) = changed_part(&prev, &prev);
        assert_eq!((x0, y0, part.dimensions()), (0, 0, (1, 1)));
    }

    #[test]
    fn long_recordings_are_decimated_and_keep_real_time() {
        let rec = moving_disc(301, 16, 24).with_frame_rate(100.0).unwrap();
        let result = SequenceResult::default();
        let axes = FigureAxes::of_recording(&rec);
        let mut animation = Animation {
            recording: &rec,
            result: &result,
            axes: &axes,
            frames: (0, 301),
        };
        assert_eq!(animation.frame_step(), 3);
        assert_eq!(animation.shown_frames().len(), 101);
        assert!(animation.shown_frames().len() <= MAX_ANIMATION_FRAMES);
        // Three 10 ms frame intervals per shown frame.
        assert_eq!(animation.delay_cs(), 3);
        let frames = decode(&animation.to_gif().unwrap());
        assert_eq!(frames.len(), 101);
        // 100 frames at 100 Hz: every second frame, 2 cs each, one second of playback (1 cs
        // frames would play at half speed, as browsers stretch them).
        animation.frames = (0, 100);
        assert_eq!((animation.frame_step(), animation.delay_cs()), (2, 2));
        // At 1 kHz every twentieth frame, 2 cs each: real time still.
        let fast = rec.clone().with_frame_rate(1000.0).unwrap();
        let fast_axes = FigureAxes::of_recording(&fast);
        animation.axes = &fast_axes;
        assert_eq!((animation.frame_step(), animation.delay_cs()), (20, 2));
        // At 31.25 Hz (32 ms) every frame, 3 cs each.
        let slow = rec.clone().with_frame_rate(31.25).unwrap();
        let slow_axes = FigureAxes::of_recording(&slow);
        animation.axes = &slow_axes;
        assert_eq!((animation.frame_step(), animation.delay_cs()), (1, 3));
        animation.frames = (0, 301);
        // Without a frame rate: 10 shown frames per second of playback.
        let unknown = FigureAxes {
            dt_s: None,
            ..axes.clone()
        };
        animation.axes = &unknown;
        animation.frames = (0, 10);
        assert_eq!(animation.delay_cs(), DEFAULT_GIF_DELAY_CS);
        animation.frames = (5, 400);
        assert!(animation.to_gif().is_err());
    }
}
