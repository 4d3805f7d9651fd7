//! Figures a reader understands: the matches between two objects and the node tracks of a
//! recording, drawn with `plotters` as PNG or SVG.
//!
//! Every figure has axes in millimetres when the sensor pitch is known (in sensels or pixels
//! otherwise, and the axis label says which), a title naming the frames (0-based) and their times,
//! a legend beside the plot (never over the data) and, where a pressure image is shown, a colour
//! bar in the recording's pressure units. Axes keep an equal aspect ratio, so shapes are not
//! distorted, and y grows downwards as in the pressure image (row 0 at the top).
//!
//! Text is set in DejaVu Sans, bundled in the crate: PNG text is rasterised from it (see the
//! `text` module) and SVG text is laid out with its metrics and names it as the font family. No
//! system font is ever looked up, so a figure looks the same on every machine, fonts or none.
//!
//! The caller describes the recording once in a [`FigureAxes`] and labels the objects with
//! [`ObjectLabel`]; [`MatchFigure`], [`TracksFigure`], [`PeakFigure`] and [`CurvesFigure`] then
//! render with `to_png` / `to_svg`,
//! and [`Animation`] plays a run's frames back as an animated GIF.

use modal_core::{MatchPair, Shape, Topology};
use pedo_io::Grid;
use pedo_io::{IoError, Result};
use pedo_track::{SequenceObject, SequenceResult, SequenceSink};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontStyle;
use std::ops::Range;

mod animation;
mod measure_figures;
mod register_figures;
mod stance_curves_figure;
mod text;

pub use animation::{Animation, DEFAULT_GIF_DELAY_CS, MAX_ANIMATION_FRAMES, MIN_GIF_DELAY_CS};
pub use measure_figures::{MeasureFigure, MeasureImage, RegionFigure};
pub use register_figures::RegisteredStackFigure;
pub use stance_curves_figure::{mean_and_sd, StanceCurvesFigure};

/// The bundled font (DejaVu Sans; licence in `fonts/LICENSE-DejaVu.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");
/// The family name under which the bundled font is registered. It is also the CSS font-family
/// an SVG carries, so viewers that have DejaVu Sans show exactly the laid-out text.
const FONT: &str = "DejaVu Sans, sans-serif";

const TITLE_SIZE: f64 = 21.0;
const SUBTITLE_SIZE: f64 = 17.0;
const LABEL_SIZE: f64 = 18.0;
const TICK_SIZE: f64 = 17.0;
const LEGEND_SIZE: f64 = 17.0;

/// Longer side of the plot area in pixels; the other side follows the data's aspect ratio.
const PLOT_LONG_SIDE: f64 = 520.0;
/// Shorter side of the plot area at least (the data range is widened to keep equal aspect).
const PLOT_SHORT_SIDE: f64 = 300.0;
const TITLE_HEIGHT: u32 = 58;
const X_LABEL_AREA: u32 = 50;
const Y_LABEL_AREA: u32 = 66;
const PLOT_MARGIN: u32 = 10;
const LEGEND_ROW: i32 = 24;

// Okabe–Ito colours: distinguishable with the common colour-vision deficiencies.
const COLOR_A: RGBColor = RGBColor(0, 114, 178);
const COLOR_B: RGBColor = RGBColor(213, 94, 0);
const COLOR_MATCH: RGBColor = RGBColor(140, 140, 140);
const COLOR_EXCESS: RGBColor = RGBColor(204, 121, 167);
const COLOR_UNMATCHED: RGBColor = RGBColor(0, 0, 0);
const COLOR_SUBTITLE: RGBColor = RGBColor(70, 70, 70);
const COLOR_GRID: RGBColor = RGBColor(228, 228, 228);
const TRACK_PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(120, 60, 160),
    RGBColor(160, 120, 20),
];

/// What a figure needs to know about the recording its objects come from: the physical scale of
/// the coordinates, the frame timing and the pressure units.
#[derive(Debug, Clone, PartialEq)]
pub struct FigureAxes {
    /// Millimetres per coordinate unit along x (columns) and y (rows); `None` draws the axes in
    /// the coordinates' own unit, named by [`data_unit`](Self::data_unit).
    pub pitch_mm: Option<[f64; 2]>,
    /// Name of the coordinate unit when the pitch is unknown: `"sensels"`, `"pixels"`, ...
    pub data_unit: String,
    /// Seconds between frames, when known: the time of frame `f` is `f * dt_s`.
    pub dt_s: Option<f64>,
    /// Pressure units for colour bars (`"kPa"`, ...); empty when unknown.
    pub pressure_units: String,
}

impl FigureAxes {
    /// The axes of a recording's objects (coordinates in sensels, as the crate produces them):
    /// its pitch, frame interval and units. Image inputs count in pixels, plates in sensels.
    pub fn of_recording(recording: &pedo_io::Recording) -> Self {
        let is_image = matches!(
            recording.format,
            Some(pedo_io::Format::Png | pedo_io::Format::Tiff)
        );
        Self {
            pitch_mm: recording.pitch_mm,
            data_unit: if is_image { "pixels" } else { "sensels" }.to_string(),
            dt_s: recording.dt_s,
            pressure_units: recording.units.clone(),
        }
    }

    /// Axes in a plain coordinate unit (e.g. `"sensels"`, or the unit of a point file), with no
    /// timing and no pressure units.
    pub fn unscaled(data_unit: impl Into<String>) -> Self {
        Self {
            pitch_mm: None,
            data_unit: data_unit.into(),
            dt_s: None,
            pressure_units: String::new(),
        }
    }

    /// The pitch when it is usable: both components finite and positive.
    fn pitch(&self) -> Option<[f64; 2]> {
        self.pitch_mm
            .filter(|p| p.iter().all(|v| v.is_finite() && *v > 0.0))
    }

    /// A point in coordinate units → the plotted unit (mm when the pitch is known).
    fn to_plot(&self, p: [f64; 2]) -> (f64, f64) {
        match self.pitch() {
            Some([dx, dy]) => (p[0] * dx, p[1] * dy),
            None => (p[0], p[1]),
        }
    }

    fn axis_unit(&self) -> String {
        match self.pitch() {
            Some(_) => "mm".to_string(),
            None if self.data_unit.is_empty() => "coordinate units".to_string(),
            None => self.data_unit.clone(),
        }
    }

    fn time_s(&self, frame: usize) -> Option<f64> {
        self.dt_s
            .filter(|dt| dt.is_finite() && *dt > 0.0)
            .map(|dt| frame as f64 * dt)
    }

    /// `"frame 40, 1.280 s"`, or `"frame 40"` without a frame rate.
    fn frame_text(&self, frame: usize) -> String {
        match self.time_s(frame) {
            Some(t) => format!("frame {frame}, {t:.3} s"),
            None => format!("frame {frame}"),
        }
    }

    fn pressure_label(&self, what: &str) -> String {
        if self.pressure_units.is_empty() {
            format!("{what} (units unknown)")
        } else {
            format!("{what} ({})", self.pressure_units)
        }
    }
}

/// How an object is named in a title: a name (`"object 12"`, a file name) and, when it comes
/// from a recording, its frame (0-based).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjectLabel {
    /// What the object is called (`"object 12"`, a file name).
    pub name: String,
    /// Its frame in the recording (0-based), shown with its time when the frame rate is known;
    /// `None` for an object that comes from no recording.
    pub frame: Option<usize>,
}

impl ObjectLabel {
    /// `"object {id}"` in frame `frame`.
    pub fn object(id: usize, frame: usize) -> Self {
        Self {
            name: format!("object {id}"),
            frame: Some(frame),
        }
    }

    fn text(&self, axes: &FigureAxes) -> String {
        match self.frame {
            Some(f) => format!("{} ({})", self.name, axes.frame_text(f)),
            None => self.name.clone(),
        }
    }
}

/// Two objects and their correspondences: A's and B's outlines (closed contours) or nodes
/// (surface points projected on x, y), one segment per one-to-one match, excess matches dashed,
/// and the nodes left unmatched ringed.
#[derive(Debug, Clone)]
pub struct MatchFigure<'a> {
    /// The first object (coordinates as [`axes`](Self::axes) describe them).
    pub a: &'a Shape,
    /// The second object.
    pub b: &'a Shape,
    /// The matches: node indices into `a` and `b` (as in [`modal_core::MatchResult::pairs`]).
    pub pairs: &'a [MatchPair],
    /// Units, timing and pressure units of the objects' recording.
    pub axes: &'a FigureAxes,
    /// How the title names the first object.
    pub label_a: ObjectLabel,
    /// How the title names the second object.
    pub label_b: ObjectLabel,
}

/// Node tracks over a pressure image, with its colour bar: one line per track for the
/// `max_tracks` longest tracks spanning at least `min_steps` objects (thousands of overlapping
/// tracks would hide each other), a dot where each starts.
///
/// Tracks across frames get a colour each, over the recording's peak-pressure image. Tracks of
/// an isocontour run (every object an isobaric level of one frame) are coloured by level, the
/// levels marked in their colours on the pressure bar, over that frame's pressure image: the
/// level, not the time, orders their steps. [`tracks_background`] picks the image.
#[derive(Debug, Clone)]
pub struct TracksFigure<'a> {
    /// The run whose tracks are drawn.
    pub result: &'a SequenceResult,
    /// The pressure image under the tracks, in the objects' coordinates (see
    /// [`tracks_background`]).
    pub background: &'a Grid,
    /// Units, timing and pressure units of the run's recording.
    pub axes: &'a FigureAxes,
    /// Tracks with fewer steps (objects) are not drawn; at least 2 is used whatever is set.
    pub min_steps: usize,
    /// At most this many tracks are drawn, the longest first.
    pub max_tracks: usize,
}

/// The image a [`TracksFigure`] of run `r` is drawn over: the frame whose isobaric levels an
/// isocontour run matched, else the recording's peak-pressure image.
pub fn tracks_background(recording: &pedo_io::Recording, r: &SequenceResult) -> Result<Grid> {
    match iso_frame(r) {
        Some(frame) => recording.frame(frame),
        None => Ok(recording.peak_image()),
    }
}

/// The frame of an isocontour run (every object has a level and all share one frame).
fn iso_frame(r: &SequenceResult) -> Option<usize> {
    let first = r.objects.first()?;
    let one_frame = r.objects.iter().all(|o| o.frame == first.frame);
    (one_frame && r.objects.iter().all(|o| o.level.is_some())).then_some(first.frame)
}

impl MatchFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        render_png(&self.layout()?)
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        render_svg(&self.layout()?)
    }

    fn layout(&self) -> Result<Layout> {
        let project = |s: &Shape| -> Result<Vec<(f64, f64)>> {
            if s.dim() < 2 {
                return Err(IoError::invalid(format!(
                    "a match figure needs 2-D or 3-D points, got {}-D",
                    s.dim()
                )));
            }
            Ok((0..s.len())
                .map(|i| {
                    let p = s.point(i);
                    self.axes.to_plot([p[0], p[1]])
                })
                .collect())
        };
        let (pa, pb) = (project(self.a)?, project(self.b)?);
        let mut matched_a = vec![false; pa.len()];
        let mut matched_b = vec![false; pb.len()];
        let mut segments = Vec::with_capacity(self.pairs.len());
        let mut excess = Vec::new();
        for m in self.pairs {
            if m.a >= pa.len() || m.b >= pb.len() {
                return Err(IoError::invalid(format!(
                    "match ({}, {}) names a node outside objects of {} and {} nodes",
                    m.a,
                    m.b,
                    pa.len(),
                    pb.len()
                )));
            }
            matched_a[m.a] = true;
            matched_b[m.b] = true;
            let seg = [pa[m.a], pb[m.b]];
            if m.excess {
                excess.push(seg);
            } else {
                segments.push(seg);
            }
        }
        let unmatched: Vec<(f64, f64)> = pa
            .iter()
            .zip(&matched_a)
            .chain(pb.iter().zip(&matched_b))
            .filter(|(_, m)| !**m)
            .map(|(p, _)| *p)
            .collect();
        let closed = |s: &Shape| matches!(s.topology(), Topology::ClosedContour);
        let title = format!(
            "{} \u{2192} {}",
            self.label_a.text(self.axes),
            self.label_b.text(self.axes)
        );
        let subtitle = format!(
            "A: {} nodes, B: {} nodes; {} matches ({} excess)",
            pa.len(),
            pb.len(),
            self.pairs.len(),
            excess.len()
        );
        let shape_entry = |name: &str, s: &Shape, color| {
            let kind = if closed(s) { "contour" } else { "nodes" };
            LegendEntry {
                text: format!("{name} {kind}"),
                glyph: if closed(s) {
                    Glyph::LineDot(color)
                } else {
                    Glyph::Dot(color)
                },
            }
        };
        let legend = vec![
            shape_entry("A", self.a, COLOR_A),
            shape_entry("B", self.b, COLOR_B),
            LegendEntry {
                text: format!("matched ({})", segments.len()),
                glyph: Glyph::Line(COLOR_MATCH),
            },
            LegendEntry {
                text: format!("excess ({})", excess.len()),
                glyph: Glyph::Dashed(COLOR_EXCESS),
            },
            LegendEntry {
                text: format!("unmatched ({})", unmatched.len()),
                glyph: Glyph::Ring(COLOR_UNMATCHED),
            },
        ];
        let bounds = Bounds::of(pa.iter().chain(&pb).copied())
            .ok_or_else(|| IoError::invalid("a match figure needs at least one finite node"))?;
        let outline = |pts: &[(f64, f64)], s: &Shape| {
            if closed(s) && pts.len() > 2 {
                let mut ring = pts.to_vec();
                ring.push(pts[0]);
                Some(ring)
            } else {
                None
            }
        };
        let mut layers = Vec::new();
        layers.extend(segments.into_iter().map(|s| Layer::Line {
            points: s.to_vec(),
            color: COLOR_MATCH,
            width: 1,
        }));
        layers.extend(excess.into_iter().map(|s| Layer::Dashed {
            points: s.to_vec(),
            color: COLOR_EXCESS,
        }));
        for (pts, s, color) in [(&pa, self.a, COLOR_A), (&pb, self.b, COLOR_B)] {
            if let Some(ring) = outline(pts, s) {
                layers.push(Layer::Line {
                    points: ring,
                    color,
                    width: 2,
                });
            }
            layers.push(Layer::Dots {
                points: pts.clone(),
                color,
                radius: 2,
            });
        }
        layers.push(Layer::Rings {
            points: unmatched,
            color: COLOR_UNMATCHED,
            radius: 5,
        });
        Ok(Layout::new(
            bounds, self.axes, title, subtitle, legend, None, layers,
        ))
    }
}

impl TracksFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        self.gathered()?.to_png(self.background, self.axes)
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        self.gathered()?.to_svg(self.background, self.axes)
    }

    /// The run's events gathered as a [`TracksGather`].
    fn gathered(&self) -> Result<TracksGather> {
        let mut g = TracksGather::new(self.min_steps, self.max_tracks);
        pedo_track::replay_result(self.result, &mut g)?;
        Ok(g)
    }
}

/// A track a [`TracksGather`] keeps: its steps, its first (object, node), each step's position
/// in sensels and its object's level.
type GatheredTrack = (usize, (usize, usize), Vec<([f64; 2], Option<f64>)>);

/// What a tracks figure ([`TracksFigure`]) draws of a run, gathered from its events
/// ([`SequenceSink`]) in memory bounded whatever the recording's length: the `max_tracks`
/// longest tracks spanning at least `min_steps` objects (ties by their first object and node),
/// each as its nodes' positions, how many tracks were long enough, the frames of the objects and,
/// for an isocontour run (every object a level of one frame), the levels.
#[derive(Debug, Clone)]
pub struct TracksGather {
    min_steps: usize,
    max_tracks: usize,
    /// The longest tracks so far, longest first: (steps, first (object, node), each step's
    /// position in sensels and its object's level).
    chosen: Vec<GatheredTrack>,
    eligible: usize,
    objects: usize,
    frames: Option<(usize, usize)>,
    /// Every object so far has a level and lies in one frame; their levels while so.
    iso: bool,
    levels: Vec<f64>,
}

impl TracksGather {
    /// An empty gathering for a figure of the `max_tracks` longest tracks spanning at least
    /// `min_steps` objects (2 at least whatever is set).
    pub fn new(min_steps: usize, max_tracks: usize) -> Self {
        Self {
            min_steps: min_steps.max(2),
            max_tracks,
            chosen: Vec::new(),
            eligible: 0,
            objects: 0,
            frames: None,
            iso: true,
            levels: Vec::new(),
        }
    }

    /// The frame of an isocontour run (every object has a level and all share one frame).
    pub fn iso_frame(&self) -> Option<usize> {
        match self.frames {
            Some((f0, f1)) if self.iso && f0 == f1 => Some(f0),
            _ => None,
        }
    }

    /// The image the figure is drawn over: the frame whose isobaric levels an isocontour run
    /// matched, else the recording's peak-pressure image.
    pub fn background(&self, recording: &pedo_io::Recording) -> Result<Grid> {
        match self.iso_frame() {
            Some(frame) => recording.frame(frame),
            None => Ok(recording.peak_image()),
        }
    }

    /// The figure over `background` as PNG bytes.
    pub fn to_png(&self, background: &Grid, axes: &FigureAxes) -> Result<Vec<u8>> {
        render_png(&self.layout(background, axes)?)
    }

    /// The figure over `background` as a standalone SVG document.
    pub fn to_svg(&self, background: &Grid, axes: &FigureAxes) -> Result<String> {
        render_svg(&self.layout(background, axes)?)
    }

    fn layout(&self, background: &Grid, axes: &FigureAxes) -> Result<Layout> {
        let shown = &self.chosen;
        let iso = self.iso_frame().map(|frame| (frame, self.level_range()));
        let mut lines = Vec::new();
        let mut starts = Vec::new();
        for (k, (_, _, steps)) in shown.iter().enumerate() {
            let steps: Vec<TrackStep> = steps
                .iter()
                .map(|&(p, level)| (axes.to_plot(p), level))
                .collect();
            let colour = |level: Option<f64>| match (iso, level) {
                (Some((_, range)), Some(l)) => level_color(l, range),
                _ => TRACK_PALETTE[k % TRACK_PALETTE.len()],
            };
            starts.push(Layer::Dots {
                points: vec![steps[0].0],
                color: colour(steps[0].1),
                radius: 4,
            });
            if iso.is_some() {
                // One segment a step, in the colour of the level it leaves.
                lines.extend(steps.windows(2).map(|w| Layer::Line {
                    points: vec![w[0].0, w[1].0],
                    color: colour(w[0].1),
                    width: 2,
                }));
            } else {
                lines.push(Layer::Line {
                    points: steps.iter().map(|s| s.0).collect(),
                    color: colour(None),
                    width: 2,
                });
            }
        }
        lines.extend(starts);
        let (bounds, mut image) = pressure_image(background, axes)?;
        let (title, subtitle, legend) = match iso {
            Some((frame, range)) => {
                if let Some(image) = &mut image {
                    image.label = axes.pressure_label(&format!("pressure, frame {frame}"));
                    image.marks = self
                        .levels
                        .iter()
                        .map(|&l| (l, level_color(l, range)))
                        .collect();
                }
                self.iso_texts(axes, frame, range, shown.len())
            }
            None => self.frame_texts(axes, shown.len()),
        };
        Ok(Layout::new(
            bounds, axes, title, subtitle, legend, image, lines,
        ))
    }

    /// The lowest and highest isobaric level of the run's objects.
    fn level_range(&self) -> [f64; 2] {
        self.levels
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &l| {
                [lo.min(l), hi.max(l)]
            })
    }

    /// Title, subtitle and legend of tracks across frames.
    fn frame_texts(&self, axes: &FigureAxes, shown: usize) -> (String, String, Vec<LegendEntry>) {
        let title = match self.frames {
            Some((f0, f1)) => {
                let times = match (axes.time_s(f0), axes.time_s(f1)) {
                    (Some(t0), Some(t1)) => format!(" ({t0:.3}\u{2013}{t1:.3} s)"),
                    _ => String::new(),
                };
                format!("Node tracks, frames {f0}\u{2013}{f1}{times}")
            }
            None => "Node tracks (no objects)".to_string(),
        };
        let subtitle = format!(
            "the {shown} longest of {} tracks spanning \u{2265} {} objects, over the peak \
             pressure",
            self.eligible, self.min_steps
        );
        (
            title,
            subtitle,
            track_legend("node track (a colour each)", TRACK_PALETTE[0]),
        )
    }

    /// Title, subtitle and legend of tracks across the isobaric levels of `frame`.
    fn iso_texts(
        &self,
        axes: &FigureAxes,
        frame: usize,
        [lo, hi]: [f64; 2],
        shown: usize,
    ) -> (String, String, Vec<LegendEntry>) {
        let units = match axes.pressure_units.as_str() {
            "" => String::new(),
            u => format!(" {u}"),
        };
        let title = format!(
            "Node tracks across {} isobaric levels, {}",
            self.objects,
            axes.frame_text(frame)
        );
        let subtitle = format!(
            "levels {lo:.0}\u{2013}{hi:.0}{units}; the {shown} longest of {} tracks \
             spanning \u{2265} {} levels",
            self.eligible, self.min_steps
        );
        let mut legend = track_legend("node track (colour: level)", level_color(lo, [lo, hi]));
        legend.push(LegendEntry {
            text: "isobaric level (on the bar)".to_string(),
            glyph: Glyph::Line(level_color(hi, [lo, hi])),
        });
        (title, subtitle, legend)
    }
}

impl SequenceSink for TracksGather {
    fn frame_objects(&mut self, _: usize, objects: &[SequenceObject]) -> Result<()> {
        for o in objects {
            self.objects += 1;
            self.frames = Some(match self.frames {
                Some((f0, f1)) => (f0.min(o.frame), f1.max(o.frame)),
                None => (o.frame, o.frame),
            });
            match o.level {
                Some(l) if self.iso => self.levels.push(l),
                _ => {
                    self.iso = false;
                    self.levels = Vec::new();
                }
            }
            if self.frames.is_some_and(|(f0, f1)| f0 != f1) {
                self.iso = false;
                self.levels = Vec::new();
            }
        }
        Ok(())
    }

    fn track(
        &mut self,
        _: usize,
        steps: &[(&SequenceObject, usize)],
        _: Option<f64>,
    ) -> Result<()> {
        if steps.len() < self.min_steps {
            return Ok(());
        }
        self.eligible += 1;
        // Longest first; ties by first object and node so the choice is deterministic.
        let key = |len: usize, first: (usize, usize)| (std::cmp::Reverse(len), first);
        let first = (steps[0].0.id, steps[0].1);
        let new = key(steps.len(), first);
        let at = self
            .chosen
            .partition_point(|(len, f, _)| key(*len, *f) < new);
        if at >= self.max_tracks {
            return Ok(());
        }
        let nodes = steps
            .iter()
            .map(|&(o, n)| {
                let p = o.shape.point(n);
                ([p[0], p[1]], o.level)
            })
            .collect();
        self.chosen.insert(at, (steps.len(), first, nodes));
        self.chosen.truncate(self.max_tracks);
        Ok(())
    }
}

/// The recording's peak-pressure image (the largest value of every sensel over the frames) with
/// the outlines of its contact regions: where the foot loaded the plate at all.
#[derive(Debug, Clone)]
pub struct PeakFigure<'a> {
    /// The peak-pressure image, one value per sensel.
    pub peak: &'a Grid,
    /// The contact outlines of the peak image, closed polygons in sensels.
    pub outlines: &'a [Vec<[f64; 2]>],
    /// Units, timing and pressure units of the recording.
    pub axes: &'a FigureAxes,
    /// The frames the image covers, `start..end`.
    pub frames: (usize, usize),
}

impl PeakFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        render_png(&self.layout()?)
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        render_svg(&self.layout()?)
    }

    fn layout(&self) -> Result<Layout> {
        let (bounds, image) = pressure_image(self.peak, self.axes)?;
        let layers = self
            .outlines
            .iter()
            .filter(|o| o.len() > 2)
            .map(|o| Layer::Line {
                points: o
                    .iter()
                    .chain(o.first())
                    .map(|p| self.axes.to_plot(*p))
                    .collect(),
                color: COLOR_A,
                width: 2,
            })
            .collect();
        let (f0, f1) = (
            self.frames.0,
            self.frames.1.saturating_sub(1).max(self.frames.0),
        );
        let times = match (self.axes.time_s(f0), self.axes.time_s(f1)) {
            (Some(t0), Some(t1)) => format!(" ({t0:.3}\u{2013}{t1:.3} s)"),
            _ => String::new(),
        };
        let title = format!("Peak pressure, frames {f0}\u{2013}{f1}{times}");
        let subtitle = format!(
            "the largest value of every sensel; {} of the contact region",
            pedo_io::counted(self.outlines.len(), "outline")
        );
        let legend = vec![LegendEntry {
            text: "contact outline".to_string(),
            glyph: Glyph::Line(COLOR_A),
        }];
        Ok(Layout::new(
            bounds, self.axes, title, subtitle, legend, image, layers,
        ))
    }
}

/// One curve of a [`CurvesFigure`]: a quantity per frame.
#[derive(Debug, Clone)]
pub struct Curve<'a> {
    /// The quantity and its unit, as the axis names it (`"total force (N)"`).
    pub label: String,
    /// One value per frame of [`CurvesFigure::frames`].
    pub values: &'a [f64],
}

/// Quantities over time, one panel each sharing the time axis (seconds when the frame rate is
/// known, else frames): the total force and the contact area of every frame of a run.
#[derive(Debug, Clone)]
pub struct CurvesFigure<'a> {
    /// The frames (0-based), in order.
    pub frames: &'a [usize],
    /// The curves, top to bottom.
    pub curves: Vec<Curve<'a>>,
    /// Units, timing and pressure units of the recording.
    pub axes: &'a FigureAxes,
}

impl CurvesFigure<'_> {
    /// The figure as PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>> {
        render_png(&self.layout()?)
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String> {
        render_svg(&self.layout()?)
    }

    fn layout(&self) -> Result<CurvesLayout> {
        if self.curves.is_empty() || self.frames.is_empty() {
            return Err(IoError::invalid(
                "a curves figure needs a curve and a frame",
            ));
        }
        let n = self.frames.len();
        if let Some(c) = self.curves.iter().find(|c| c.values.len() != n) {
            return Err(IoError::invalid(format!(
                "the curve {:?} has {} values for {n} frames",
                c.label,
                c.values.len()
            )));
        }
        let x: Vec<f64> = self
            .frames
            .iter()
            .map(|&f| self.axes.time_s(f).unwrap_or(f as f64))
            .collect();
        let timed = self.axes.time_s(0).is_some();
        let (f0, f1) = (self.frames[0], self.frames[n - 1]);
        let times = match (self.axes.time_s(f0), self.axes.time_s(f1)) {
            (Some(t0), Some(t1)) => format!(" ({t0:.3}\u{2013}{t1:.3} s)"),
            _ => String::new(),
        };
        Ok(CurvesLayout {
            title: format!("Load over time, frames {f0}\u{2013}{f1}{times}"),
            subtitle: format!("every frame of the run ({})", pedo_io::counted(n, "frame")),
            x_desc: if timed { "time (s)" } else { "frame" }.to_string(),
            x,
            panels: self
                .curves
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    // A value that is not finite breaks the line instead of hiding the curve.
                    (
                        c.label.clone(),
                        c.values.to_vec(),
                        TRACK_PALETTE[k % TRACK_PALETTE.len()],
                    )
                })
                .collect(),
        })
    }
}

/// A [`CurvesFigure`] laid out: a title and one panel a curve.
struct CurvesLayout {
    title: String,
    subtitle: String,
    x_desc: String,
    x: Vec<f64>,
    panels: Vec<(String, Vec<f64>, RGBColor)>,
}

/// The plot area of one panel of a curves figure, in pixels.
const CURVE_PLOT: (u32, u32) = (640, 180);

impl Drawing for CurvesLayout {
    fn size(&self) -> (u32, u32) {
        let panels = self.panels.len() as u32;
        let width = (Y_LABEL_AREA + 24 + CURVE_PLOT.0 + 2 * PLOT_MARGIN).max(
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
        let finite = |v: &&f64| v.is_finite();
        let (x0, x1) = self
            .x
            .iter()
            .filter(finite)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let (x0, x1) = if x1 > x0 {
            (x0, x1)
        } else {
            (x0 - 0.5, x0 + 0.5)
        };
        let panels = self.panels.len() as u32;
        let mut rest = body;
        for (k, (label, values, color)) in self.panels.iter().enumerate() {
            let last = k as u32 + 1 == panels;
            let height = CURVE_PLOT.1 + PLOT_MARGIN + if last { X_LABEL_AREA } else { 0 };
            let height = height.min(h.saturating_sub(TITLE_HEIGHT));
            let (area, below) = rest.split_vertically(height);
            rest = below;
            let top_value = values.iter().filter(finite).fold(0.0f64, |m, &v| m.max(v));
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
                .build_cartesian_2d(x0..x1, 0.0..y1)
                .map_err(figure_error)?;
            let x_fmt = tick_formatter(x1 - x0, 8);
            let y_fmt = tick_formatter(y1, 4);
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(label.as_str())
                .label_style((FONT, TICK_SIZE))
                .axis_desc_style((FONT, LABEL_SIZE * 0.8))
                .x_labels(8)
                .y_labels(4)
                .x_label_formatter(&x_fmt)
                .y_label_formatter(&y_fmt)
                .bold_line_style(COLOR_GRID.stroke_width(1))
                .light_line_style(TRANSPARENT.stroke_width(0))
                .axis_style(BLACK.stroke_width(1));
            if last {
                mesh.x_desc(self.x_desc.as_str());
            }
            mesh.draw().map_err(figure_error)?;
            // One line per run of finite values.
            let points: Vec<(f64, f64)> =
                self.x.iter().copied().zip(values.iter().copied()).collect();
            for piece in points.split(|(x, y)| !(x.is_finite() && y.is_finite())) {
                if piece.len() == 1 {
                    chart
                        .draw_series(std::iter::once(Circle::new(piece[0], 2, color.filled())))
                        .map_err(figure_error)?;
                } else if piece.len() > 1 {
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            piece.to_vec(),
                            color.stroke_width(2),
                        )))
                        .map_err(figure_error)?;
                }
            }
        }
        Ok(())
    }
}

/// The plot's extent (the whole image `g`, in sensels) and the image with its colour bar
/// (none for an image without load).
fn pressure_image(g: &Grid, axes: &FigureAxes) -> Result<(Bounds, Option<PressureImage>)> {
    let (rows, cols) = (g.rows(), g.cols());
    let corner = |c: f64, r: f64| axes.to_plot([c, r]);
    let mut bounds = Bounds::of([
        corner(-0.5, -0.5),
        corner(cols as f64 - 0.5, rows as f64 - 0.5),
    ])
    .ok_or_else(|| IoError::invalid("the pressure image has no finite extent"))?;
    bounds.pad = false;
    let max = g.max();
    let image = (max.is_finite() && max > 0.0)
        .then(|| PressureImage::of_grid(g, corner, max, axes.pressure_label("peak pressure")));
    Ok((bounds, image))
}

/// A track's node in plotted units, with its object's isobaric level (isocontour runs).
type TrackStep = ((f64, f64), Option<f64>);

/// The legend of a tracks figure: a track line described by `text`, and its start.
fn track_legend(text: &str, color: RGBColor) -> Vec<LegendEntry> {
    vec![
        LegendEntry {
            text: text.to_string(),
            glyph: Glyph::Line(color),
        },
        LegendEntry {
            text: "track start".to_string(),
            glyph: Glyph::Dot(color),
        },
    ]
}

/// The colour of isobaric level `l` within `[lo, hi]`: dark purple to orange (the "plasma"
/// scale without its pale yellow end, which would vanish on the light grey of low pressure).
fn level_color(l: f64, [lo, hi]: [f64; 2]) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (13.0, 8.0, 135.0),
        (126.0, 3.0, 168.0),
        (204.0, 71.0, 120.0),
        (237.0, 121.0, 83.0),
        (253.0, 180.0, 47.0),
    ];
    let t = if hi > lo {
        ((l - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - k as f64;
    let mix = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Extent of the plotted data, in plotted units.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    x: [f64; 2],
    y: [f64; 2],
    /// Add a margin around the data (points); images fill the plot exactly.
    pad: bool,
}

impl Bounds {
    fn of(points: impl IntoIterator<Item = (f64, f64)>) -> Option<Self> {
        let mut b = Bounds {
            x: [f64::INFINITY, f64::NEG_INFINITY],
            y: [f64::INFINITY, f64::NEG_INFINITY],
            pad: true,
        };
        for (x, y) in points {
            if x.is_finite() && y.is_finite() {
                b.x = [b.x[0].min(x), b.x[1].max(x)];
                b.y = [b.y[0].min(y), b.y[1].max(y)];
            }
        }
        (b.x[0] <= b.x[1]).then_some(b)
    }

    /// The plotted ranges and the plot area's size in pixels, at equal scale on both axes.
    fn fit(self) -> (Range<f64>, Range<f64>, (u32, u32)) {
        let span = |r: [f64; 2]| r[1] - r[0];
        let longest = span(self.x).max(span(self.y)).max(1e-9);
        let pad = if self.pad { 0.06 * longest } else { 0.0 };
        let mut x = [self.x[0] - pad, self.x[1] + pad];
        let mut y = [self.y[0] - pad, self.y[1] + pad];
        let longest = span(x).max(span(y));
        // Widen the shorter range (about its centre) so the plot is never a thin strip.
        let short = longest * PLOT_SHORT_SIDE / PLOT_LONG_SIDE;
        for r in [&mut x, &mut y] {
            if span(*r) < short {
                let c = 0.5 * (r[0] + r[1]);
                *r = [c - 0.5 * short, c + 0.5 * short];
            }
        }
        let scale = PLOT_LONG_SIDE / longest;
        let size = (
            (span(x) * scale).round() as u32,
            (span(y) * scale).round() as u32,
        );
        (x[0]..x[1], y[0]..y[1], size)
    }
}

/// What is drawn inside the plot area, in plotted units, bottom layer first.
enum Layer {
    Line {
        points: Vec<(f64, f64)>,
        color: RGBColor,
        width: u32,
    },
    Dashed {
        points: Vec<(f64, f64)>,
        color: RGBColor,
    },
    Dots {
        points: Vec<(f64, f64)>,
        color: RGBColor,
        radius: i32,
    },
    Rings {
        points: Vec<(f64, f64)>,
        color: RGBColor,
        radius: i32,
    },
}

/// A pressure image: one rectangle per loaded sensel, coloured by value, with its colour bar.
struct PressureImage {
    cells: Vec<([(f64, f64); 2], f64)>,
    max: f64,
    label: String,
    /// Values marked across the colour bar in their colours (the levels of isocontour tracks).
    marks: Vec<(f64, RGBColor)>,
}

impl PressureImage {
    /// Every loaded sensel (value above 0) of `g` as a cell between its edges on the plot
    /// (`corner` maps a sensel position to plot coordinates), shaded up to `max`.
    fn of_grid(g: &Grid, corner: impl Fn(f64, f64) -> (f64, f64), max: f64, label: String) -> Self {
        let cells = (0..g.rows())
            .flat_map(|row| (0..g.cols()).map(move |col| (row, col)))
            .filter_map(|(row, col)| {
                let v = g.get(row, col);
                (v > 0.0).then(|| {
                    let (x0, y0) = corner(col as f64 - 0.5, row as f64 - 0.5);
                    let (x1, y1) = corner(col as f64 + 0.5, row as f64 + 0.5);
                    ([(x0, y0), (x1, y1)], v)
                })
            })
            .collect();
        PressureImage {
            cells,
            max,
            label,
            marks: Vec::new(),
        }
    }
}

/// Light to dark grey, so that coloured lines stay visible over high pressure. The grey follows
/// the square root of the pressure, so that the lightly loaded outline of the foot stays visible
/// next to the peaks; the colour bar shows the same mapping against a linear pressure scale.
fn pressure_color(v: f64, max: f64) -> RGBColor {
    let t = (v / max).clamp(0.0, 1.0).sqrt();
    let g = (235.0 - 150.0 * t).round() as u8;
    RGBColor(g, g, g)
}

#[derive(Clone, Copy)]
enum Glyph {
    Line(RGBColor),
    LineDot(RGBColor),
    Dashed(RGBColor),
    Dot(RGBColor),
    Ring(RGBColor),
}

struct LegendEntry {
    text: String,
    glyph: Glyph,
}

/// A complete figure: title, plot with axes, optional colour bar and a legend column.
struct Layout {
    title: String,
    subtitle: String,
    x_desc: String,
    y_desc: String,
    x_range: Range<f64>,
    y_range: Range<f64>,
    plot: (u32, u32),
    legend: Vec<LegendEntry>,
    image: Option<PressureImage>,
    layers: Vec<Layer>,
    /// Widen the figure to its title and subtitle when they are wider than the plot and its
    /// columns (off for an animation, whose frames share one size while their titles vary).
    fit_title: bool,
}

const COLORBAR_WIDTH: u32 = 104;
/// The legend column: glyphs from `LEGEND_GLYPH.0` to `.1`, text from `LEGEND_TEXT_X`, and a
/// margin after the longest text.
const LEGEND_GLYPH: (i32, i32) = (14, 42);
const LEGEND_TEXT_X: i32 = 52;
const LEGEND_MARGIN: u32 = 16;
/// Space left and right of the title and subtitle.
const TITLE_MARGIN: u32 = 16;
const MAX_SIDE: u32 = 4096;

/// The bundled font, parsed once for the text measures and the bitmap backend.
fn bundled_font() -> Option<&'static ab_glyph::FontRef<'static>> {
    static FONT_REF: std::sync::OnceLock<Option<ab_glyph::FontRef<'static>>> =
        std::sync::OnceLock::new();
    FONT_REF
        .get_or_init(|| ab_glyph::FontRef::try_from_slice(FONT_BYTES).ok())
        .as_ref()
}

/// The width in pixels of `text` in the bundled font at `size`.
fn text_width(text: &str, size: f64) -> u32 {
    match bundled_font() {
        Some(font) => text::text_width(font, text, size),
        // The font is compiled in and always parses; a generous estimate keeps text uncut.
        None => (0.7 * size * text.chars().count() as f64).ceil() as u32,
    }
}

impl Layout {
    fn new(
        bounds: Bounds,
        axes: &FigureAxes,
        title: String,
        subtitle: String,
        legend: Vec<LegendEntry>,
        image: Option<PressureImage>,
        layers: Vec<Layer>,
    ) -> Self {
        let (x_range, y_range, plot) = bounds.fit();
        let unit = axes.axis_unit();
        Self {
            title,
            subtitle,
            x_desc: format!("x ({unit})"),
            y_desc: format!("y ({unit})"),
            x_range,
            y_range,
            plot,
            legend,
            image,
            layers,
            fit_title: true,
        }
    }

    fn chart_width(&self) -> u32 {
        Y_LABEL_AREA + self.plot.0 + 2 * PLOT_MARGIN
    }

    /// The legend column's width: its longest text measured in the bundled font, so that no
    /// entry is cut at the figure's right edge.
    fn legend_width(&self) -> u32 {
        let longest = self.legend.iter().map(|e| text_width(&e.text, LEGEND_SIZE));
        LEGEND_TEXT_X as u32 + longest.max().unwrap_or(0) + LEGEND_MARGIN
    }

    fn size(&self) -> (u32, u32) {
        let bar = if self.image.is_some() {
            COLORBAR_WIDTH
        } else {
            0
        };
        let legend_height = LEGEND_ROW as u32 * (self.legend.len() as u32 + 1);
        let body = (self.plot.1 + X_LABEL_AREA + PLOT_MARGIN).max(legend_height);
        let title =
            text_width(&self.title, TITLE_SIZE).max(text_width(&self.subtitle, SUBTITLE_SIZE));
        let mut width = self.chart_width() + bar + self.legend_width();
        if self.fit_title {
            width = width.max(title + 2 * TITLE_MARGIN);
        }
        (width.min(MAX_SIDE), (TITLE_HEIGHT + body).min(MAX_SIDE))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(figure_error)?;
        let (w, _) = root.dim_in_pixel();
        let (top, body) = root.split_vertically(TITLE_HEIGHT);
        draw_title(&top, w, &self.title, &self.subtitle)?;
        let (chart_area, rest) = body.split_horizontally(self.chart_width());
        self.draw_chart(&chart_area)?;
        let legend_area = match &self.image {
            Some(image) => {
                let (bar_area, legend_area) = rest.split_horizontally(COLORBAR_WIDTH);
                draw_colorbar(&bar_area, image)?;
                legend_area
            }
            None => rest,
        };
        draw_legend(&legend_area, &self.legend)
    }

    fn draw_chart<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let (x0, x1) = (self.x_range.start, self.x_range.end);
        let (y0, y1) = (self.y_range.start, self.y_range.end);
        // y grows downwards, as in the pressure image: the top of the plot is the smallest y.
        let mut chart = ChartBuilder::on(area)
            .margin(PLOT_MARGIN)
            .margin_top(0)
            .x_label_area_size(X_LABEL_AREA)
            .y_label_area_size(Y_LABEL_AREA)
            .build_cartesian_2d(x0..x1, y1..y0)
            .map_err(figure_error)?;
        // About one tick label per 70 px, so that labels never touch.
        let (x_ticks, y_ticks) = (
            (self.plot.0 as usize / 70).max(3),
            (self.plot.1 as usize / 60).max(3),
        );
        let x_fmt = tick_formatter(x1 - x0, x_ticks);
        let y_fmt = tick_formatter(y1 - y0, y_ticks);
        chart
            .configure_mesh()
            .x_desc(&self.x_desc)
            .y_desc(&self.y_desc)
            .label_style((FONT, TICK_SIZE))
            .axis_desc_style((FONT, LABEL_SIZE))
            .x_labels(x_ticks)
            .y_labels(y_ticks)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .bold_line_style(COLOR_GRID.stroke_width(1))
            .light_line_style(TRANSPARENT.stroke_width(0))
            .axis_style(BLACK.stroke_width(1))
            .draw()
            .map_err(figure_error)?;
        if let Some(image) = &self.image {
            chart
                .draw_series(image.cells.iter().map(|&(corners, v)| {
                    Rectangle::new(corners, pressure_color(v, image.max).filled())
                }))
                .map_err(figure_error)?;
        }
        for layer in &self.layers {
            match layer {
                Layer::Line {
                    points,
                    color,
                    width,
                } => {
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            points.clone(),
                            color.stroke_width(*width),
                        )))
                        .map_err(figure_error)?;
                }
                Layer::Dashed { points, color } => {
                    chart
                        .draw_series(std::iter::once(DashedPathElement::new(
                            points.clone(),
                            6,
                            4,
                            color.stroke_width(2),
                        )))
                        .map_err(figure_error)?;
                }
                Layer::Dots {
                    points,
                    color,
                    radius,
                } => {
                    chart
                        .draw_series(
                            points
                                .iter()
                                .map(|&p| Circle::new(p, *radius, color.filled())),
                        )
                        .map_err(figure_error)?;
                }
                Layer::Rings {
                    points,
                    color,
                    radius,
                } => {
                    chart
                        .draw_series(
                            points
                                .iter()
                                .map(|&p| Circle::new(p, *radius, color.stroke_width(2))),
                        )
                        .map_err(figure_error)?;
                }
            }
        }
        // A frame around the plot area, as in a journal figure (drawn in pixels: the data's
        // far edges map one pixel past the area and would be clipped).
        let plot = chart.plotting_area().strip_coord_spec();
        let (pw, ph) = plot.dim_in_pixel();
        plot.draw(&Rectangle::new(
            [(0, 0), (pw as i32 - 1, ph as i32 - 1)],
            BLACK.stroke_width(1),
        ))
        .map_err(figure_error)?;
        Ok(())
    }
}

/// A vertical colour bar with the pressure scale on its right, level with the plot area.
fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    image: &PressureImage,
) -> Result<()> {
    const STEPS: usize = 64;
    let mut bar = ChartBuilder::on(area)
        .margin_top(0)
        .margin_bottom(PLOT_MARGIN)
        .margin_left(4)
        .margin_right(0)
        .x_label_area_size(X_LABEL_AREA)
        .right_y_label_area_size(COLORBAR_WIDTH - 32)
        .build_cartesian_2d(0.0..1.0, 0.0..image.max)
        .map_err(figure_error)?;
    let fmt = tick_formatter(image.max, 6);
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(&image.label)
        .label_style((FONT, TICK_SIZE))
        .axis_desc_style((FONT, LABEL_SIZE))
        .y_labels(6)
        .y_label_formatter(&fmt)
        .set_all_tick_mark_size(4)
        .axis_style(BLACK.stroke_width(1))
        .draw()
        .map_err(figure_error)?;
    let step = image.max / STEPS as f64;
    bar.draw_series((0..STEPS).map(|k| {
        let v0 = k as f64 * step;
        Rectangle::new(
            [(0.0, v0), (1.0, v0 + step)],
            pressure_color(v0 + 0.5 * step, image.max).filled(),
        )
    }))
    .map_err(figure_error)?;
    bar.draw_series(
        image
            .marks
            .iter()
            .map(|&(v, c)| PathElement::new(vec![(0.0, v), (1.0, v)], c.stroke_width(3))),
    )
    .map_err(figure_error)?;
    bar.draw_series(std::iter::once(PathElement::new(
        vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, image.max),
            (0.0, image.max),
            (0.0, 0.0),
        ],
        BLACK.stroke_width(1),
    )))
    .map_err(figure_error)?;
    Ok(())
}

/// The legend, one entry a row, in its own column beside the plot.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<()> {
    let style = TextStyle::from((FONT, LEGEND_SIZE).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let ((x0, x1), xt) = (LEGEND_GLYPH, LEGEND_TEXT_X);
    for (k, entry) in entries.iter().enumerate() {
        let y = 8 + LEGEND_ROW * k as i32;
        let line = |c: &RGBColor| PathElement::new(vec![(x0, y), (x1, y)], c.stroke_width(2));
        let mid = ((x0 + x1) / 2, y);
        match entry.glyph {
            Glyph::Line(c) => area.draw(&line(&c)),
            Glyph::LineDot(c) => area
                .draw(&line(&c))
                .and_then(|_| area.draw(&Circle::new(mid, 3, c.filled()))),
            Glyph::Dashed(c) => area.draw(&DashedPathElement::new(
                vec![(x0, y), (x1, y)],
                6,
                4,
                c.stroke_width(2),
            )),
            Glyph::Dot(c) => area.draw(&Circle::new(mid, 4, c.filled())),
            Glyph::Ring(c) => area.draw(&Circle::new(mid, 5, c.stroke_width(2))),
        }
        .map_err(figure_error)?;
        area.draw_text(&entry.text, &style, (xt, y))
            .map_err(figure_error)?;
    }
    Ok(())
}

/// Tick labels with as many decimals as the tick spacing needs: plotters places at most
/// `max_ticks` ticks at a spacing of 1, 2 or 5 times a power of ten, the finest that fits.
fn tick_formatter(range: f64, max_ticks: usize) -> impl Fn(&f64) -> String {
    let range = range.abs().max(1e-12);
    let fits = |step: f64| ((range / step).floor() as usize) < max_ticks.max(2);
    let mut power = 10f64.powf(range.log10().ceil());
    let mut step = power;
    'search: loop {
        for m in [5.0, 2.0, 1.0] {
            let candidate = power / 10.0 * m;
            if !fits(candidate) || candidate < 1e-9 {
                break 'search;
            }
            step = candidate;
        }
        power /= 10.0;
    }
    let decimals = (-step.log10() - 1e-9).ceil().clamp(0.0, 6.0) as usize;
    move |v: &f64| {
        let s = format!("{v:.decimals$}");
        // "-0" reads as a different tick from "0".
        if s.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            s.trim_start_matches('-').to_string()
        } else {
            s
        }
    }
}

/// A figure's title and subtitle, centred in the band `top` of a figure `width` pixels wide.
fn draw_title<DB: DrawingBackend>(
    top: &DrawingArea<DB, Shift>,
    width: u32,
    title: &str,
    subtitle: &str,
) -> Result<()> {
    fn centred(size: f64, color: &RGBColor) -> TextStyle<'_> {
        TextStyle::from((FONT, size).into_font())
            .color(color)
            .pos(Pos::new(HPos::Center, VPos::Center))
    }
    let x = width as i32 / 2;
    top.draw_text(title, &centred(TITLE_SIZE, &BLACK), (x, 18))
        .map_err(figure_error)?;
    top.draw_text(subtitle, &centred(SUBTITLE_SIZE, &COLOR_SUBTITLE), (x, 42))
        .map_err(figure_error)?;
    Ok(())
}

fn figure_error(e: impl std::fmt::Display) -> IoError {
    IoError::Figure(e.to_string())
}

/// Registers the bundled font with plotters once per process.
fn register_bundled_font() -> Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(IoError::Figure(
            "the bundled font could not be read".to_string(),
        ))
    }
}

/// A figure the renderers draw: its size in pixels and how it draws itself.
trait Drawing {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>;
}

impl Drawing for Layout {
    fn size(&self) -> (u32, u32) {
        Layout::size(self)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        Layout::draw(self, root)
    }
}

fn render_png(layout: &impl Drawing) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    let (w, h, pixels) = render_rgb(layout)?;
    let mut out = Vec::new();
    // Fast compression: figures are written by the hundred and stay small anyway.
    image::codecs::png::PngEncoder::new_with_quality(
        &mut out,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(&pixels, w, h, image::ExtendedColorType::Rgb8)
    .map_err(figure_error)?;
    Ok(out)
}

/// The figure as 8-bit RGB pixels, row by row: (width, height, pixels).
fn render_rgb(layout: &impl Drawing) -> Result<(u32, u32, Vec<u8>)> {
    register_bundled_font()?;
    let (w, h) = layout.size();
    let mut pixels = vec![255u8; w as usize * h as usize * 3];
    {
        let font = bundled_font()
            .cloned()
            .ok_or_else(|| IoError::Figure("the bundled font could not be read".to_string()))?;
        let root = text::TextBitmap {
            inner: BitMapBackend::with_buffer(&mut pixels, (w, h)),
            font,
        }
        .into_drawing_area();
        layout.draw(&root)?;
        root.present().map_err(figure_error)?;
    }
    Ok((w, h, pixels))
}

fn render_svg(layout: &impl Drawing) -> Result<String> {
    register_bundled_font()?;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, layout.size()).into_drawing_area();
        layout.draw(&root)?;
        root.present().map_err(figure_error)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pedo_track::Track;

    /// A closed polygon approximating an ellipse with semi-axes `rx`, `ry` around `centre`.
    fn ellipse(n: usize, centre: [f64; 2], rx: f64, ry: f64) -> Shape {
        let points: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                [centre[0] + rx * t.cos(), centre[1] + ry * t.sin()]
            })
            .collect();
        Shape::from_points_2d(&points, Topology::ClosedContour).unwrap()
    }

    /// A's first 20 nodes matched one-to-one, two excess matches, the rest unmatched.
    fn pairs() -> Vec<MatchPair> {
        let mut p: Vec<MatchPair> = (0..20)
            .map(|i| MatchPair {
                a: i,
                b: i,
                cost: 0.1,
                excess: false,
            })
            .collect();
        p.push(MatchPair {
            a: 20,
            b: 19,
            cost: 0.3,
            excess: true,
        });
        p.push(MatchPair {
            a: 21,
            b: 19,
            cost: 0.3,
            excess: true,
        });
        p
    }

    fn plate_axes() -> FigureAxes {
        FigureAxes {
            pitch_mm: Some([5.08, 5.08]),
            data_unit: "sensels".into(),
            dt_s: Some(0.032),
            pressure_units: "kPa".into(),
        }
    }

    fn decode(png: &[u8]) -> image::RgbImage {
        image::load_from_memory_with_format(png, image::ImageFormat::Png)
            .expect("a valid PNG")
            .to_rgb8()
    }

    /// Pixels in the rectangle `[x0, x1) × [y0, y1)` that are not white.
    fn inked(img: &image::RgbImage, x: Range<u32>, y: Range<u32>) -> usize {
        y.flat_map(|r| x.clone().map(move |c| (c, r)))
            .filter(|&(c, r)| img.get_pixel(c, r).0 != [255, 255, 255])
            .count()
    }

    fn count_color(img: &image::RgbImage, c: RGBColor) -> usize {
        img.pixels().filter(|p| p.0 == [c.0, c.1, c.2]).count()
    }

    #[test]
    fn match_png_has_title_plot_and_legend_drawn() {
        let (a, b) = (
            ellipse(30, [10.0, 20.0], 4.0, 9.0),
            ellipse(24, [11.0, 21.0], 4.5, 8.0),
        );
        let (pairs, axes) = (pairs(), plate_axes());
        let fig = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: ObjectLabel::object(12, 40),
            label_b: ObjectLabel::object(13, 41),
        };
        let layout = fig.layout().unwrap();
        let img = decode(&fig.to_png().unwrap());
        assert_eq!((img.width(), img.height()), layout.size());
        let (w, h) = layout.size();
        // The title band holds text; the band above the title's first line is blank margin.
        assert!(inked(&img, 0..w, 8..TITLE_HEIGHT) > 500);
        assert_eq!(inked(&img, 0..w, 0..2), 0);
        // The plot area holds both objects' colours; the legend column holds its glyphs.
        let plot_x = Y_LABEL_AREA + PLOT_MARGIN..layout.chart_width() - PLOT_MARGIN;
        let plot_y = TITLE_HEIGHT..TITLE_HEIGHT + layout.plot.1;
        let plot = image::imageops::crop_imm(
            &img,
            plot_x.start,
            plot_y.start,
            plot_x.end - plot_x.start,
            plot_y.end - plot_y.start,
        )
        .to_image();
        assert!(count_color(&plot, COLOR_A) > 50 && count_color(&plot, COLOR_B) > 50);
        assert!(count_color(&plot, COLOR_EXCESS) > 10);
        let legend = layout.chart_width()..w;
        assert!(inked(&img, legend, TITLE_HEIGHT..h) > 300);
    }

    #[test]
    fn match_svg_names_frames_times_units_and_legend() {
        let (a, b) = (
            ellipse(30, [10.0, 20.0], 4.0, 9.0),
            ellipse(24, [11.0, 21.0], 4.5, 8.0),
        );
        let (pairs, axes) = (pairs(), plate_axes());
        let fig = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: ObjectLabel::object(12, 40),
            label_b: ObjectLabel::object(13, 41),
        };
        let svg = fig.to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for text in [
            "object 12 (frame 40, 1.280 s) \u{2192} object 13 (frame 41, 1.312 s)",
            "x (mm)",
            "y (mm)",
            "A contour",
            "B contour",
            "matched (20)",
            "excess (2)",
            // A's nodes 22..29 and B's 20..23.
            "unmatched (12)",
        ] {
            assert!(svg.contains(text), "SVG lacks {text:?}");
        }
        // Tick labels in mm: the data spans about 30-150 mm vertically, so 100 is a tick.
        assert!(svg.contains(">\n100\n</text>"), "no 100 mm tick");
        assert!(svg.contains("font-family=\"DejaVu Sans, sans-serif\""));
    }

    #[test]
    fn figure_without_pitch_or_rate_says_sensels_and_frames_only() {
        let (a, b) = (
            ellipse(30, [10.0, 20.0], 4.0, 9.0),
            ellipse(24, [11.0, 21.0], 4.5, 8.0),
        );
        let pairs = pairs();
        let axes = FigureAxes::unscaled("sensels");
        let fig = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: ObjectLabel::object(0, 3),
            label_b: ObjectLabel::object(1, 4),
        };
        let svg = fig.to_svg().unwrap();
        assert!(svg.contains("x (sensels)") && svg.contains("y (sensels)"));
        assert!(!svg.contains("(mm)") && !svg.contains(" s)"));
        assert!(svg.contains("object 0 (frame 3) \u{2192} object 1 (frame 4)"));
        let rec = pedo_io::Recording::new(1, 2, 2, vec![0.0; 4], vec![true; 4]).unwrap();
        assert_eq!(FigureAxes::of_recording(&rec).axis_unit(), "sensels");
        let mut image = rec;
        image.format = Some(pedo_io::Format::Png);
        assert_eq!(FigureAxes::of_recording(&image).axis_unit(), "pixels");
    }

    #[test]
    fn surfaces_are_drawn_as_nodes_projected_on_xy() {
        let pts = |dz: f64| -> Shape {
            let p: Vec<[f64; 3]> = (0..25)
                .map(|i| [(i % 5) as f64, (i / 5) as f64 * 2.0, dz + i as f64])
                .collect();
            Shape::from_points_3d(&p, Topology::None).unwrap()
        };
        let (a, b) = (pts(0.0), pts(100.0));
        let pairs: Vec<MatchPair> = (0..25)
            .map(|i| MatchPair {
                a: i,
                b: 24 - i,
                cost: 0.0,
                excess: false,
            })
            .collect();
        let axes = FigureAxes::unscaled("sensels");
        let fig = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: ObjectLabel {
                name: "a.xyz".into(),
                frame: None,
            },
            label_b: ObjectLabel {
                name: "b.xyz".into(),
                frame: None,
            },
        };
        let svg = fig.to_svg().unwrap();
        assert!(svg.contains("A nodes") && svg.contains("a.xyz \u{2192} b.xyz"));
        // Heights (up to 124) are not plotted: the y axis covers the rows 0..8 only.
        let layout = fig.layout().unwrap();
        assert!(layout.y_range.end < 10.0 && layout.y_range.start > -1.0);
        decode(&fig.to_png().unwrap());
    }

    #[test]
    fn bad_match_indices_are_an_error_not_a_panic() {
        let (a, b) = (
            ellipse(10, [0.0, 0.0], 1.0, 1.0),
            ellipse(10, [0.0, 0.0], 1.0, 1.0),
        );
        let pairs = [MatchPair {
            a: 0,
            b: 10,
            cost: 0.0,
            excess: false,
        }];
        let axes = FigureAxes::unscaled("sensels");
        let fig = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: ObjectLabel::object(0, 0),
            label_b: ObjectLabel::object(1, 1),
        };
        assert!(matches!(fig.to_png(), Err(IoError::InvalidInput(_))));
        assert!(matches!(fig.to_svg(), Err(IoError::InvalidInput(_))));
    }

    #[test]
    fn mm_axes_keep_equal_aspect() {
        // 20 × 60 sensels at 2 mm × 1 mm: 40 mm wide, 60 mm tall.
        let b = Bounds::of([(0.0, 0.0), (40.0, 60.0)]).unwrap();
        let (x, y, (w, h)) = b.fit();
        let px_per_mm = (w as f64 / (x.end - x.start), h as f64 / (y.end - y.start));
        assert!((px_per_mm.0 - px_per_mm.1).abs() < 0.05 * px_per_mm.0);
        assert_eq!(h, PLOT_LONG_SIDE as u32);
        // A thin strip gets a widened range, not a distorted scale.
        let (x, y, (w, h)) = Bounds::of([(0.0, 0.0), (100.0, 1.0)]).unwrap().fit();
        assert!(h >= PLOT_SHORT_SIDE as u32 - 1);
        let ratio = (w as f64 / (x.end - x.start)) / (h as f64 / (y.end - y.start));
        assert!((ratio - 1.0).abs() < 0.02);
    }

    fn track_result() -> (SequenceResult, Grid) {
        let objects: Vec<SequenceObject> = (0..4)
            .map(|f| SequenceObject {
                id: f,
                frame: 10 + f,
                index: 0,
                level: None,
                shape: ellipse(16, [6.0 + f as f64 * 0.5, 8.0], 3.0, 5.0),
                measures: None,
            })
            .collect();
        let tracks = (0..16)
            .map(|n| Track {
                steps: (0..4).map(|o| (o, n)).collect(),
            })
            .collect();
        let result = SequenceResult {
            objects,
            pairs: Vec::new(),
            reference_pairs: Vec::new(),
            tracks,
            packed_tracks: None,
            track_round_trips: Vec::new(),
            splits: Vec::new(),
            merges: Vec::new(),
            skipped_frames: Vec::new(),
            skipped_pairs: Vec::new(),
            timings: Default::default(),
        };
        let (rows, cols) = (16, 12);
        let data = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64, (i % cols) as f64);
                (300.0 - 20.0 * ((r - 8.0).powi(2) / 4.0 + (c - 6.0).powi(2))).max(0.0)
            })
            .collect();
        (result, Grid::new(rows, cols, data).unwrap())
    }

    #[test]
    fn tracks_figure_has_colour_bar_with_units_and_time_span() {
        let (result, peak) = track_result();
        let axes = plate_axes();
        let fig = TracksFigure {
            result: &result,
            background: &peak,
            axes: &axes,
            min_steps: 3,
            max_tracks: 10,
        };
        let svg = fig.to_svg().unwrap();
        for text in [
            "Node tracks, frames 10\u{2013}13 (0.320\u{2013}0.416 s)",
            "the 10 longest of 16 tracks",
            "peak pressure (kPa)",
            "x (mm)",
            "node track",
            "track start",
        ] {
            assert!(svg.contains(text), "SVG lacks {text:?}");
        }
        let layout = fig
            .gathered()
            .unwrap()
            .layout(fig.background, fig.axes)
            .unwrap();
        let img = decode(&fig.to_png().unwrap());
        assert_eq!((img.width(), img.height()), layout.size());
        // The colour bar's darkest step (the peak) and the image's grey both appear.
        assert!(count_color(&img, pressure_color(300.0, 300.0)) > 20);
        assert!(count_color(&img, TRACK_PALETTE[0]) > 10);
        let no_units = FigureAxes::unscaled("sensels");
        let fig = TracksFigure {
            axes: &no_units,
            ..fig
        };
        assert!(fig
            .to_svg()
            .unwrap()
            .contains("peak pressure (units unknown)"));
    }

    /// Columns of ink (any non-white pixel) within `margin` pixels of the right edge.
    fn ink_at_right_edge(img: &image::RgbImage, margin: u32) -> usize {
        inked(img, img.width() - margin..img.width(), 0..img.height())
    }

    #[test]
    fn no_text_is_cut_at_the_right_edge() {
        // The legend column is as wide as its longest entry: "node track (a colour each)" was
        // cut to "node track (a colour e" by a fixed-width column.
        let (result, peak) = track_result();
        let axes = plate_axes();
        let tracks = TracksFigure {
            result: &result,
            background: &peak,
            axes: &axes,
            min_steps: 3,
            max_tracks: 10,
        };
        let (a, b) = (
            ellipse(30, [10.0, 20.0], 4.0, 9.0),
            ellipse(24, [11.0, 21.0], 4.5, 8.0),
        );
        let pairs = pairs();
        let long = ObjectLabel {
            name: "a rather long object name at 1234 kPa".to_string(),
            frame: Some(40),
        };
        let matches = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: long.clone(),
            label_b: long,
        };
        for png in [tracks.to_png().unwrap(), matches.to_png().unwrap()] {
            let img = decode(&png);
            assert_eq!(ink_at_right_edge(&img, 8), 0, "text reaches the right edge");
            // ... nor the left edge (a title wider than the plots is centred in a wider figure).
            assert_eq!(inked(&img, 0..4, 0..TITLE_HEIGHT), 0);
        }
    }

    #[test]
    fn isocontour_tracks_are_coloured_by_level_over_their_frame() {
        // Every object an isobaric level of frame 8: the levels, not the time, order the steps.
        let (mut result, _) = track_result();
        for (k, o) in result.objects.iter_mut().enumerate() {
            o.frame = 8;
            o.level = Some(50.0 + 60.0 * k as f64);
        }
        let (rows, cols) = (16, 12);
        let frame = Grid::new(rows, cols, vec![120.0; rows * cols]).unwrap();
        let axes = plate_axes();
        let fig = TracksFigure {
            result: &result,
            background: &frame,
            axes: &axes,
            min_steps: 3,
            max_tracks: 10,
        };
        let svg = fig.to_svg().unwrap();
        for text in [
            "Node tracks across 4 isobaric levels, frame 8, 0.256 s",
            "levels 50\u{2013}230 kPa",
            "spanning \u{2265} 3 levels",
            "pressure, frame 8 (kPa)",
            "node track (colour: level)",
        ] {
            assert!(svg.contains(text), "SVG lacks {text:?}");
        }
        for absent in ["frames 8\u{2013}8", "peak pressure", "objects"] {
            assert!(!svg.contains(absent), "SVG has {absent:?}");
        }
        let img = decode(&fig.to_png().unwrap());
        // The lowest and highest levels' colours: on the tracks and marked on the bar.
        for level in [50.0, 230.0] {
            let c = level_color(level, [50.0, 230.0]);
            assert!(count_color(&img, c) > 10, "level {level} not drawn");
        }
        assert_eq!(ink_at_right_edge(&img, 8), 0);
    }

    #[test]
    fn png_rendering_is_deterministic_and_independent_of_system_fonts() {
        // Text comes only from the bundled font: two renderings are identical byte for byte,
        // and the title's glyphs are drawn (dark pixels in the title band).
        let (a, b) = (
            ellipse(30, [10.0, 20.0], 4.0, 9.0),
            ellipse(24, [11.0, 21.0], 4.5, 8.0),
        );
        let (pairs, axes) = (pairs(), plate_axes());
        let fig = MatchFigure {
            a: &a,
            b: &b,
            pairs: &pairs,
            axes: &axes,
            label_a: ObjectLabel::object(12, 40),
            label_b: ObjectLabel::object(13, 41),
        };
        let png = fig.to_png().unwrap();
        assert_eq!(png, fig.to_png().unwrap());
        let img = decode(&png);
        let dark = (0..TITLE_HEIGHT)
            .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0.iter().all(|&v| v < 80))
            .count();
        assert!(dark > 200, "title text missing ({dark} dark pixels)");
    }

    #[test]
    fn tick_labels_have_the_decimals_their_spacing_needs() {
        // 150 mm with at most 8 ticks: every 20 mm.
        assert_eq!(tick_formatter(150.0, 8)(&40.0), "40");
        // 3 units with 8 ticks: every 0.5; with 4 ticks: every 1.
        assert_eq!(tick_formatter(3.0, 8)(&0.5), "0.5");
        assert_eq!(tick_formatter(3.0, 8)(&-0.0), "0.0");
        assert_eq!(tick_formatter(3.0, 4)(&2.0), "2");
        // 0.06 with 7 ticks: every 0.01.
        assert_eq!(tick_formatter(0.06, 7)(&0.03), "0.03");
    }
}
