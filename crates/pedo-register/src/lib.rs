//! Footprints registered across trials (docs/method.md, "Registering footprints"): each
//! trial's images carried onto one template's grid, for pixel-wise statistics.
//!
//! Per trial: the whole-foot outline (the convex hull of every sensel its peak image loads,
//! [`footprint`]), the template's outline matched onto it by modal matching (modal-core,
//! the outline recipe) with a prior that a footprint never turns over (a candidate map that
//! mirrors or turns by more than [`RegisterParams::max_turn`] is refused), the thin-plate
//! [`CorrespondenceField`] of the matches (from the template's plane to the trial's), or the
//! footprints' principal axes when they fit the images better (`start`); an affine correction
//! and a non-rigid B-spline step by the images (`refine`, `warp`); and every image of the trial
//! sampled (bilinear) at the map's image of each template sensel. No files, no terminal: the front
//! ends read the recordings and pedo-output writes the results.

mod band;
pub mod footprint;
pub mod refine;
mod start;
pub mod warp;

use footprint::{bilinear, distance_to_polygon, hull_of_mask, loaded_mask};
use modal_core::matching::prealign::rotation_angle;
use modal_core::{Affine, CorrespondenceField, MatchOptions, MatchPair, Refine, Shape, Topology};
use pedo_io::measures::Measures;
use pedo_io::{IoError, Result};
use rayon::prelude::*;

modal_core::option_set! {
    /// How footprints are registered (`pedomatch register`, `pymodal.register`): each option
    /// declared here once.
    RegisterParams {
        let _d = ();
        /// The template: `first`, `study`, `mun104` or a file.
        template: String = "first".to_string();
            Value, "first",
            "The template every trial is registered onto: first (the first trial), study (a study template: the trials registered onto their median-sized trial, averaged, and registered again, template_rounds times), mun104 (the bundled MUN104 right-foot peak image of Pataky et al. 2011, 63 x 27 sensels; mun104-left for the left foot's) or a file (a recording, whose peak image is taken).";
        /// Mirror every trial left-right before registering it.
        mirror_left: bool = false;
            Flag, false,
            "Mirror every trial left-right before registering it: left feet onto a right-foot template.";
        /// Largest turn of the template onto a trial, in degrees.
        max_turn: f64 = 45.0;
            Value, 45.0,
            "Largest turn, in degrees, of the map of the template's outline onto a trial's: a footprint does not turn heel to toe. A map that turns further, or mirrors, is refused and the trial aligned by the footprints' principal axes alone (centroids, the axes' turn within this bound, the areas' ratio; the fallback column of registration.csv).";
        /// Nodes of each whole-foot outline.
        outline_nodes: usize = 64;
            Value, 64,
            "Nodes of each whole-foot outline (the convex hull of every loaded sensel), evenly spaced.";
        /// Smoothing of the thin-plate field, λ (0 interpolates the matches).
        field_smoothing: f64 = 1.0;
            Value, 1.0,
            "Smoothing of the thin-plate field fitted to the outlines' matches (lambda, in sensels squared as scipy's RBFInterpolator smoothing); 0 interpolates them exactly.";
        /// Rounds of the study template.
        template_rounds: usize = 2;
            Value, 2,
            "Rounds of the study template (template study): register, average, register again.";
        /// Refine each map by the images' intensities.
        refine_intensity: bool = true;
            NegatedFlag, true,
            "Refine each trial's map by the images: an affine correction of the outline's field, and of the footprints' principal axes, that lowers the mean squared difference of the peak images (Levenberg-Marquardt, on the images blurred by 1.5 sensels, then as they are), the better of the two kept. --no-refine-intensity registers by the outlines alone.";
        /// Spacing of the non-rigid intensity step's control points, in sensels (0: none).
        warp_spacing: f64 = 6.0;
            Value, 6.0,
            "Spacing, in template sensels, of the control points of the non-rigid step after the affine correction: a cubic B-spline displacement fitted to the peak images (Levenberg-Marquardt on the mean squared difference with a bending penalty, blurred by 1.5 sensels, then as they are, then on a lattice of half the spacing; no step may fold the map). 0 leaves it out; so does --no-refine-intensity.";
        /// Weight of the non-rigid step's bending penalty.
        warp_smoothing: f64 = 1e-4;
            Value, 1e-4,
            "Weight of the bending penalty of the non-rigid step (the control grid's squared second differences, times the template's mean squared value): larger is stiffer.";
        /// A sensel is part of a footprint above this peak value.
        foot_threshold: f64 = 0.0;
            Value, 0.0,
            "A sensel belongs to a footprint when its peak value is above this (the file's units).";
    }
}

impl RegisterParams {
    /// Checks every value.
    pub fn validate(&self) -> std::result::Result<(), modal_core::OptionError> {
        use modal_core::OptionError;
        if !(self.max_turn.is_finite() && (0.0..=180.0).contains(&self.max_turn)) {
            return Err(OptionError::new(
                "max_turn",
                self.max_turn,
                "a number of degrees in [0, 180]",
            ));
        }
        if self.outline_nodes < 8 {
            return Err(OptionError::new(
                "outline_nodes",
                self.outline_nodes,
                "an integer >= 8",
            ));
        }
        if !(self.field_smoothing.is_finite() && self.field_smoothing >= 0.0) {
            return Err(OptionError::new(
                "field_smoothing",
                self.field_smoothing,
                "a finite number >= 0",
            ));
        }
        if !(self.warp_spacing.is_finite() && self.warp_spacing >= 0.0) {
            return Err(OptionError::new(
                "warp_spacing",
                self.warp_spacing,
                "a finite number of sensels >= 0",
            ));
        }
        if !(self.warp_smoothing.is_finite() && self.warp_smoothing >= 0.0) {
            return Err(OptionError::new(
                "warp_smoothing",
                self.warp_smoothing,
                "a finite number >= 0",
            ));
        }
        if !self.foot_threshold.is_finite() {
            return Err(OptionError::new(
                "foot_threshold",
                self.foot_threshold,
                "a finite number",
            ));
        }
        if self.template.trim().is_empty() {
            return Err(OptionError::new(
                "template",
                "''",
                "first, study, mun104, mun104-left or a file",
            ));
        }
        Ok(())
    }

    /// What [`template`](Self::template) names.
    pub fn template_source(&self) -> TemplateName {
        match self.template.trim() {
            "first" => TemplateName::First,
            "study" => TemplateName::Study,
            "mun104" | "mun104-right" => TemplateName::Mun104Right,
            "mun104-left" => TemplateName::Mun104Left,
            other => TemplateName::File(other.into()),
        }
    }
}

/// The register options' declarations ([`RegisterParams`]).
pub fn register_option_specs() -> Vec<modal_core::OptionSpec> {
    RegisterParams::specs()
}

/// What a `template` option names.
#[derive(Debug, Clone, PartialEq)]
pub enum TemplateName {
    /// The first trial.
    First,
    /// A study template, built from the trials.
    Study,
    /// The bundled MUN104 right-foot template.
    Mun104Right,
    /// The bundled MUN104 left-foot template.
    Mun104Left,
    /// A file, read by the front end.
    File(std::path::PathBuf),
}

/// The images of one footprint, `rows × cols` row-major (NaN: no sensor, read as 0): the peak
/// image always, the pressure-time integral and the mean pressure when the trial is a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct FootImages {
    /// Rows of the grid.
    pub rows: usize,
    /// Columns of the grid.
    pub cols: usize,
    /// Peak pressure per sensel.
    pub peak: Vec<f64>,
    /// Pressure-time integral per sensel, when known.
    pub pti: Option<Vec<f64>>,
    /// Mean pressure over each sensel's loaded frames, when known.
    pub mean: Option<Vec<f64>>,
}

impl FootImages {
    /// A footprint of its peak image alone.
    ///
    /// # Errors
    /// [`IoError::InvalidInput`] for an empty grid, a length other than `rows × cols` or an
    /// infinite value.
    pub fn from_peak(rows: usize, cols: usize, peak: Vec<f64>) -> Result<Self> {
        let f = Self {
            rows,
            cols,
            peak,
            pti: None,
            mean: None,
        };
        f.check()?;
        Ok(f)
    }

    /// The peak, PTI and mean images of a recording's measures.
    pub fn from_measures(m: &Measures) -> Self {
        Self {
            rows: m.rows,
            cols: m.cols,
            peak: m.peak.clone(),
            pti: Some(m.pti.clone()),
            mean: Some(m.mean.clone()),
        }
    }

    /// The peak, PTI and mean images of every frame of a recording (a sensel loaded above 0:
    /// one footprint per recording).
    ///
    /// # Errors
    /// [`IoError::NoObject`] for a recording without any load (no footprint);
    /// [`IoError::InvalidInput`] for one without frames.
    pub fn of_recording(recording: &pedo_io::Recording) -> Result<Self> {
        if recording.n_frames() > 0 && !recording.peak_image().data().iter().any(|&v| v > 0.0) {
            return Err(IoError::no_object(
                "no sensel is loaded in any frame: there is no footprint to register",
            ));
        }
        let m = Measures::of_recording(recording, 0.0, 0..recording.n_frames())?;
        Ok(Self::from_measures(&m))
    }

    fn check(&self) -> Result<()> {
        if self.rows == 0 || self.cols == 0 {
            return Err(IoError::invalid(format!(
                "a footprint image of {} x {} sensels is empty",
                self.rows, self.cols
            )));
        }
        for (name, layer) in self.layers() {
            if layer.len() != self.rows * self.cols {
                return Err(IoError::invalid(format!(
                    "the {name} image holds {} values, not {} x {}",
                    layer.len(),
                    self.rows,
                    self.cols
                )));
            }
            if layer.iter().any(|v| v.is_infinite()) {
                return Err(IoError::invalid(format!(
                    "the {name} image holds an infinite value"
                )));
            }
        }
        Ok(())
    }

    /// The images held, named (`peak`, `pti`, `mean`).
    pub fn layers(&self) -> Vec<(&'static str, &[f64])> {
        let mut out = vec![("peak", self.peak.as_slice())];
        if let Some(p) = &self.pti {
            out.push(("pti", p.as_slice()));
        }
        if let Some(m) = &self.mean {
            out.push(("mean", m.as_slice()));
        }
        out
    }

    /// The footprint mirrored left-right (column `c` to `cols − 1 − c`).
    pub fn mirrored(&self) -> Self {
        let flip = |v: &[f64]| -> Vec<f64> {
            v.chunks_exact(self.cols)
                .flat_map(|row| row.iter().rev().copied())
                .collect()
        };
        Self {
            rows: self.rows,
            cols: self.cols,
            peak: flip(&self.peak),
            pti: self.pti.as_deref().map(flip),
            mean: self.mean.as_deref().map(flip),
        }
    }
}

/// The bundled MUN104 peak-pressure template (Pataky, Bosch & Rosenbaum 2011, MIT; 63 × 27
/// sensels), of the right foot or the left.
pub fn mun104(right: bool) -> FootImages {
    let text = if right {
        include_str!("../data/MUN104R.csv")
    } else {
        include_str!("../data/MUN104L.csv")
    };
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse::<f64>().unwrap_or(0.0))
                .collect()
        })
        .collect();
    let cols = rows.first().map_or(0, Vec::len);
    FootImages {
        rows: rows.len(),
        cols,
        peak: rows.concat(),
        pti: None,
        mean: None,
    }
}

/// A template: its images, its footprint mask and whole-foot outline.
#[derive(Debug, Clone, PartialEq)]
pub struct Template {
    /// The template's images (a study template: the means of the registered trials).
    pub images: FootImages,
    /// Its footprint: the sensels loaded above the threshold (a study template: those of at
    /// least half of the registered trials).
    pub mask: Vec<bool>,
    /// Its whole-foot outline, `outline_nodes` points.
    pub outline: Vec<[f64; 2]>,
}

impl Template {
    /// The template of `images` with footprint `mask`.
    ///
    /// # Errors
    /// [`IoError::NoObject`] when the mask loads fewer than 3 sensels or no area.
    pub fn with_mask(images: FootImages, mask: Vec<bool>, nodes: usize) -> Result<Self> {
        images.check()?;
        let outline = outline_of(&mask, images.rows, images.cols, nodes)
            .map_err(|e| e.of_input("the template"))?;
        Ok(Self {
            images,
            mask,
            outline,
        })
    }

    /// The template of `images`, its footprint the sensels whose peak is above `threshold`.
    ///
    /// # Errors
    /// As [`with_mask`](Self::with_mask).
    pub fn of_images(images: FootImages, threshold: f64, nodes: usize) -> Result<Self> {
        let mask = loaded_mask(&images.peak, threshold);
        Self::with_mask(images, mask, nodes)
    }
}

fn outline_of(mask: &[bool], rows: usize, cols: usize, nodes: usize) -> Result<Vec<[f64; 2]>> {
    let hull = hull_of_mask(mask, rows, cols)?;
    pedo_io::contour::resample_closed(&hull, nodes)
}

/// One trial registered onto the template: its images on the template's grid, its footprint
/// there, the map of the match and the quality of the registration.
#[derive(Debug, Clone, PartialEq)]
pub struct Registration {
    /// The trial's images sampled on the template's grid.
    pub images: FootImages,
    /// The trial's footprint on the template's grid.
    pub mask: Vec<bool>,
    /// The affine map of the match, template sensels to the trial's: `x' = M x + t`.
    pub affine: [[f64; 3]; 2],
    /// The turn of that map, in degrees (signed, counter-clockwise in (column, row)).
    pub turn_deg: f64,
    /// Its scale, `√det M`.
    pub scale: f64,
    /// Whether the match was refused by the prior (it mirrored or turned further than
    /// `max_turn`) and the trial aligned by the footprints' principal axes alone.
    pub fallback: bool,
    /// Which map was kept: the identity when every map overlapped the template worse than the
    /// unregistered trial (the map then reported is the identity).
    pub kept: MapKept,
    /// RMS distance, in the trial's sensels, from the field's image of each template outline
    /// node to the trial's outline.
    pub residual_sensels: f64,
    /// Sensels in one footprint but not the other (template and registered trial), as a
    /// percentage of the template's footprint.
    pub mask_xor_pct: f64,
    /// Pearson correlation of the registered peak image with the template's over the union of
    /// the two footprints; `None` when one of them is constant there.
    pub correlation: Option<f64>,
}

/// Every trial of a study registered onto one template.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRegistration {
    /// The template the trials were registered onto.
    pub template: Template,
    /// One registration per trial, in the trials' order.
    pub trials: Vec<Registration>,
}

/// The blurs (Gaussian σ, sensels) of the intensity refinement's stages, coarse to fine.
const REFINE_BLURS: [f64; 2] = [1.5, 0.0];
/// Weight of the footprints' masks beside the peak pressures in the non-rigid step (relative to
/// the template's mean squared value; chosen on the tuning subjects, BENCHMARKS.md).
const WARP_MASK_WEIGHT: f64 = 0.5;
/// Levenberg–Marquardt iterations per stage of the non-rigid step, at most: each costs a pass
/// over every sensel and a solve of the control grid's normal equations.
const WARP_ITERATIONS: usize = 12;
/// Iterations of the non-rigid step's last stage, on a lattice of half the spacing (chosen on
/// the tuning subjects: 12 fitted no closer than 6, BENCHMARKS.md).
const WARP_FINE_ITERATIONS: usize = 6;
/// Levenberg–Marquardt iterations per stage (at most; fewer when a step no longer helps).
const REFINE_ITERATIONS: usize = 20;

/// Where the template comes from, once the front end has read any file.
#[derive(Debug, Clone, PartialEq)]
pub enum TemplateSource {
    /// One of the trials (after mirroring, when the trials are mirrored).
    Trial(usize),
    /// A study template built from the trials in `rounds` rounds.
    Study {
        /// Rounds of register-and-average.
        rounds: usize,
    },
    /// Given images (a file's peak image, the bundled template).
    Images(FootImages),
}

impl RegisterParams {
    /// The source of the template of these options with a file's images, when it names a file
    /// (`read` reads it).
    ///
    /// # Errors
    /// What `read` returns.
    pub fn resolve_template(
        &self,
        read: impl FnOnce(&std::path::Path) -> Result<FootImages>,
    ) -> Result<TemplateSource> {
        Ok(match self.template_source() {
            TemplateName::First => TemplateSource::Trial(0),
            TemplateName::Study => TemplateSource::Study {
                rounds: self.template_rounds,
            },
            TemplateName::Mun104Right => TemplateSource::Images(mun104(true)),
            TemplateName::Mun104Left => TemplateSource::Images(mun104(false)),
            TemplateName::File(p) => TemplateSource::Images(read(&p)?),
        })
    }
}

/// Registers every trial onto the template `source` names, the trials in parallel on the rayon
/// pool.
///
/// # Errors
/// [`IoError::InvalidInput`] for no trials, a trial index beyond them or invalid images;
/// [`IoError::NoObject`] for a footprint with fewer than 3 loaded sensels (naming the trial);
/// [`IoError::Option`] for an invalid option; a field that cannot be fitted
/// ([`IoError::Shape`]).
pub fn register_trials(
    trials: &[FootImages],
    source: &TemplateSource,
    params: &RegisterParams,
) -> Result<StudyRegistration> {
    params.validate()?;
    if trials.is_empty() {
        return Err(IoError::invalid("no trials to register".to_string()));
    }
    for (i, t) in trials.iter().enumerate() {
        t.check().map_err(|e| e.of_input(&format!("trial {i}")))?;
    }
    let trials: Vec<FootImages> = if params.mirror_left {
        trials.iter().map(FootImages::mirrored).collect()
    } else {
        trials.to_vec()
    };
    let prepared: Vec<Prepared> = trials
        .par_iter()
        .enumerate()
        .map(|(i, t)| Prepared::new(t, params).map_err(|e| e.of_input(&format!("trial {i}"))))
        .collect::<Result<_>>()?;
    let template = match source {
        TemplateSource::Trial(i) => {
            let t = trials.get(*i).ok_or_else(|| {
                IoError::invalid(format!(
                    "template trial {i} is beyond the {}",
                    pedo_io::counted(trials.len(), "trial")
                ))
            })?;
            Template::of_images(t.clone(), params.foot_threshold, params.outline_nodes)?
        }
        TemplateSource::Images(images) => {
            Template::of_images(images.clone(), params.foot_threshold, params.outline_nodes)?
        }
        TemplateSource::Study { rounds } => {
            // Start from the trial of median footprint area: neither the smallest nor the
            // largest foot decides the grid's shape.
            let mut order: Vec<usize> = (0..trials.len()).collect();
            order.sort_by_key(|&i| prepared[i].area);
            let start = order[order.len() / 2];
            let mut template = Template::of_images(
                trials[start].clone(),
                params.foot_threshold,
                params.outline_nodes,
            )?;
            // The rounds average rigidly registered trials: the mean is a template, not a trial,
            // and the non-rigid step would triple the study's time for a sharper mean only.
            let rounds_params = RegisterParams {
                warp_spacing: 0.0,
                ..params.clone()
            };
            for _ in 0..*rounds {
                let regs = register_prepared(&prepared, &template, &rounds_params)?;
                template = average_template(&regs, &template, params.outline_nodes)?;
            }
            template
        }
    };
    let regs = register_prepared(&prepared, &template, params)?;
    Ok(StudyRegistration {
        template,
        trials: regs,
    })
}

/// Registers one trial onto `template`.
///
/// # Errors
/// As [`register_trials`].
pub fn register_one(
    trial: &FootImages,
    template: &Template,
    params: &RegisterParams,
) -> Result<Registration> {
    params.validate()?;
    trial.check()?;
    let trial = if params.mirror_left {
        trial.mirrored()
    } else {
        trial.clone()
    };
    let p = Prepared::new(&trial, params)?;
    register_with(&p, template, params)
}

/// A trial with its outline.
struct Prepared<'a> {
    images: std::borrow::Cow<'a, FootImages>,
    mask: Vec<bool>,
    outline: Vec<[f64; 2]>,
    area: usize,
}

impl<'a> Prepared<'a> {
    fn new(t: &'a FootImages, params: &RegisterParams) -> Result<Self> {
        let mask = loaded_mask(&t.peak, params.foot_threshold);
        let outline = outline_of(&mask, t.rows, t.cols, params.outline_nodes)?;
        let area = mask.iter().filter(|&&m| m).count();
        Ok(Self {
            images: std::borrow::Cow::Borrowed(t),
            mask,
            outline,
            area,
        })
    }
}

fn register_prepared(
    prepared: &[Prepared<'_>],
    template: &Template,
    params: &RegisterParams,
) -> Result<Vec<Registration>> {
    prepared
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            register_with(p, template, params).map_err(|e| e.of_input(&format!("trial {i}")))
        })
        .collect()
}

/// The mean of registered trials as a template: mean images, the sensels of at least half of
/// the trials' footprints.
fn average_template(regs: &[Registration], like: &Template, nodes: usize) -> Result<Template> {
    let (rows, cols) = (like.images.rows, like.images.cols);
    let n = regs.len() as f64;
    let mean_of = |get: &dyn Fn(&Registration) -> Option<&Vec<f64>>| -> Option<Vec<f64>> {
        let mut acc = vec![0.0; rows * cols];
        for r in regs {
            for (a, v) in acc.iter_mut().zip(get(r)?) {
                *a += v / n;
            }
        }
        Some(acc)
    };
    let peak = mean_of(&|r| Some(&r.images.peak)).unwrap_or_default();
    let pti = mean_of(&|r| r.images.pti.as_ref());
    let mean = mean_of(&|r| r.images.mean.as_ref());
    let mut votes = vec![0usize; rows * cols];
    for r in regs {
        for (v, &m) in votes.iter_mut().zip(&r.mask) {
            *v += usize::from(m);
        }
    }
    let mask = votes.iter().map(|&v| 2 * v >= regs.len()).collect();
    Template::with_mask(
        FootImages {
            rows,
            cols,
            peak,
            pti,
            mean,
        },
        mask,
        nodes,
    )
}

/// The start of the outline match: the thin-plate field of its pairs and its affine map; `None`
/// when the match fails or the prior refuses it (it mirrors or turns further than `max_turn`).
fn outline_start(
    template: &[[f64; 2]],
    trial: &[[f64; 2]],
    params: &RegisterParams,
) -> Result<Option<start::Start>> {
    let a = Shape::from_points_2d(template, Topology::ClosedContour)?;
    let b = Shape::from_points_2d(trial, Topology::ClosedContour)?;
    let mut opts = MatchOptions::for_outlines();
    opts.rotation_search.max_rotation = Some(params.max_turn);
    // The turn is bounded by the prior, which the drift's centroid-and-scale start does not
    // search: the affine outline match, as measured for registration (BENCHMARKS.md).
    opts.refine = Refine::Affine;
    let Ok(m) = modal_core::match_shapes(&a, &b, &opts) else {
        return Ok(None);
    };
    let t = m.transform;
    let pairs: Vec<MatchPair> = m.pairs.into_iter().filter(|p| !p.excess).collect();
    if !(t.det() > 0.0 && rotation_angle(&t) <= params.max_turn + 1e-6 && pairs.len() >= 3) {
        return Ok(None);
    }
    Ok(Some(start::Start {
        field: CorrespondenceField::fit(&a, &b, &pairs, params.field_smoothing)?,
        map: t,
    }))
}

/// The starts of the image fit (the outline match's, when the prior accepts it, and the
/// principal axes'), each with its affine correction by the images; the one whose corrected map
/// fits the images better is returned, with the template sensels' images under its field and
/// whether the outline match was refused.
#[allow(clippy::type_complexity)]
fn chosen_start(
    template: &Template,
    p: &Prepared<'_>,
    params: &RegisterParams,
) -> Result<(start::Start, Vec<[f64; 2]>, refine::PlaneAffine, bool)> {
    let outline = outline_start(&template.outline, &p.outline, params)?;
    let fallback = outline.is_none();
    let mut starts: Vec<start::Start> = outline.into_iter().collect();
    let cols = [template.images.cols, p.images.cols];
    // Without the images there is nothing to choose by: the principal axes only stand in for a
    // refused match.
    if (fallback || params.refine_intensity)
        && let Some(map) = start::principal_axes(&template.mask, &p.mask, cols, params.max_turn)
    {
        starts.push(start::affine_start(template, map, params.field_smoothing)?);
    }
    let centres = grid_centres(template.images.rows, template.images.cols);
    let mut best: Option<(f64, start::Start, Vec<[f64; 2]>, refine::PlaneAffine)> = None;
    for st in starts {
        let points = st.field.apply(&centres);
        let (correction, cost) = if params.refine_intensity {
            image_correction(&points, template, p)
        } else {
            (refine::PlaneAffine::identity([0.0, 0.0]), 0.0)
        };
        if best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, st, points, correction));
        }
    }
    let (_, st, points, correction) = best.ok_or_else(|| {
        IoError::no_object("the footprint has no principal axes (fewer than 3 sensels)")
    })?;
    Ok((st, points, correction, fallback))
}

/// The affine correction by the images of the map `at` (the template sensels' images), and the
/// cost of the corrected map: the peak images' squared difference plus the footprints',
/// weighted as in the warp.
fn image_correction(
    at: &[[f64; 2]],
    template: &Template,
    p: &Prepared<'_>,
) -> (refine::PlaneAffine, f64) {
    let (rows, cols) = (template.images.rows, template.images.cols);
    let src = &p.images;
    let grid = |r, c, v| refine::GridImage {
        rows: r,
        cols: c,
        values: v,
    };
    let correction = refine::refine_map(
        at,
        grid(rows, cols, &template.images.peak[..]),
        grid(src.rows, src.cols, &src.peak[..]),
        &REFINE_BLURS,
        REFINE_ITERATIONS,
        &refine::AFFINE_DIRECTIONS,
    );
    let z = |v: f64| if v.is_nan() { 0.0 } else { v };
    let tpl = &template.images.peak;
    let scale = tpl.iter().map(|&v| z(v) * z(v)).sum::<f64>() / tpl.len().max(1) as f64;
    let as_f = |m: &bool| f64::from(u8::from(*m));
    let mask_f: Vec<f64> = p.mask.iter().map(as_f).collect();
    let mut cost = 0.0;
    for ((q, &t), m) in at.iter().zip(tpl).zip(&template.mask) {
        let q = correction.apply(*q);
        let v = bilinear(&src.peak, src.rows, src.cols, q[0], q[1]);
        let inside = bilinear(&mask_f, src.rows, src.cols, q[0], q[1]);
        cost += (v - z(t)).powi(2) + WARP_MASK_WEIGHT * scale * (inside - as_f(m)).powi(2);
    }
    (correction, cost)
}

/// Which map a registration kept (the last check of [`register_one`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapKept {
    /// The start's field, the affine correction and the non-rigid intensity step.
    Warp,
    /// The start's field and the affine correction, no warp (`rigid`: the warp overlapped the template worse
    /// than the unregistered trial, or there was no warp).
    Rigid,
    /// The identity: every map overlapped the template worse than the trial as it lies.
    Identity,
}

impl MapKept {
    /// Its name in `registration.csv`: `warp`, `rigid` or `identity`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Warp => "warp",
            Self::Rigid => "rigid",
            Self::Identity => "identity",
        }
    }
}

/// The template's grid and the trial's images, as the sampling needs them.
struct Sampler<'a> {
    src: &'a FootImages,
    mask_f: Vec<f64>,
    template_mask: &'a [bool],
}

impl Sampler<'_> {
    fn sample(&self, at: &[[f64; 2]], v: &[f64]) -> Vec<f64> {
        at.iter()
            .map(|q| bilinear(v, self.src.rows, self.src.cols, q[0], q[1]))
            .collect()
    }

    /// The trial's footprint carried onto the template's grid by `at`.
    fn mask(&self, at: &[[f64; 2]]) -> Vec<bool> {
        self.sample(at, &self.mask_f)
            .iter()
            .map(|&v| v >= 0.5)
            .collect()
    }

    fn xor(&self, mask: &[bool]) -> usize {
        mask.iter()
            .zip(self.template_mask)
            .filter(|(a, b)| a != b)
            .count()
    }
}

/// The map of the template's sensels into the trial's plane: the start's field, the
/// `correction` by the images, the non-rigid step; the points before the non-rigid step and
/// after.
fn fitted_points(
    start: &[[f64; 2]],
    template: &Template,
    trial: &Prepared<'_>,
    params: &RegisterParams,
    correction: refine::PlaneAffine,
) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let src = &trial.images;
    let (rows, cols) = (template.images.rows, template.images.cols);
    let grid = |r, c, v| refine::GridImage {
        rows: r,
        cols: c,
        values: v,
    };
    let (tpl, img) = (
        grid(rows, cols, &template.images.peak[..]),
        grid(src.rows, src.cols, &src.peak[..]),
    );
    let mut at = start.to_vec();
    if !params.refine_intensity {
        return (at.clone(), at);
    }
    for q in &mut at {
        *q = correction.apply(*q);
    }
    let settings = warp::WarpSettings {
        spacing: params.warp_spacing,
        smoothing: params.warp_smoothing,
        blurs: REFINE_BLURS,
        iterations: WARP_ITERATIONS,
        fine_spacing: params.warp_spacing / 2.0,
        fine_smoothing: params.warp_smoothing,
        fine_iterations: WARP_FINE_ITERATIONS,
        mask_weight: WARP_MASK_WEIGHT,
    };
    let as_f = |m: &[bool]| -> Vec<f64> { m.iter().map(|&b| f64::from(u8::from(b))).collect() };
    let (tm, sm) = (as_f(&template.mask), as_f(&trial.mask));
    let images = warp::WarpImages {
        template: tpl,
        trial: img,
        template_mask: &tm,
        trial_mask: &sm,
    };
    let warped = warp::refine_warp(&at, &images, &settings);
    (at, warped)
}

fn grid_centres(rows: usize, cols: usize) -> Vec<[f64; 2]> {
    (0..rows * cols)
        .map(|i| [(i % cols) as f64, (i / cols) as f64])
        .collect()
}

fn register_with(
    p: &Prepared<'_>,
    template: &Template,
    params: &RegisterParams,
) -> Result<Registration> {
    let (start, start_points, fitted_correction, fallback) = chosen_start(template, p, params)?;
    let (field, t) = (&start.field, &start.map);
    let (rows, cols) = (template.images.rows, template.images.cols);
    let src = &p.images;
    let s = Sampler {
        src,
        mask_f: p.mask.iter().map(|&m| f64::from(u8::from(m))).collect(),
        template_mask: &template.mask,
    };
    // Never worse than the trial as it lies: the last check keeps the first of the warp, the
    // map without it (`rigid`) and the identity whose footprint overlaps the template's at least as well as
    // the unregistered trial's does (a registration that moved the footprint's edge away is
    // no registration for pixel-wise statistics). When both maps fail, the correction by the
    // images may be what went astray (it fits pressures, which may lie in another basin than
    // the outline's): the warp and the start's field without the correction are tried too.
    let identity = grid_centres(rows, cols);
    let identity_mask = s.mask(&identity);
    let xor_identity = s.xor(&identity_mask);
    let mut correction = refine::PlaneAffine::identity([0.0, 0.0]);
    let mut kept = None;
    for correct in [true, false] {
        if !correct && !params.refine_intensity {
            break;
        }
        correction = if correct {
            fitted_correction
        } else {
            refine::PlaneAffine::identity([0.0, 0.0])
        };
        let (rigid_at, warped_at) = fitted_points(&start_points, template, p, params, correction);
        kept = first_overlapping(&s, [rigid_at, warped_at], params, xor_identity);
        if kept.is_some() {
            break;
        }
    }
    let (kind, at, mask) = kept.unwrap_or((MapKept::Identity, identity, identity_mask));
    let images = FootImages {
        rows,
        cols,
        peak: s.sample(&at, &src.peak),
        pti: src.pti.as_deref().map(|v| s.sample(&at, v)),
        mean: src.mean.as_deref().map(|v| s.sample(&at, v)),
    };
    let outline_image = outline_image(field, &correction, template, (&start_points, &at), kind);
    let residual_sensels = (outline_image
        .iter()
        .map(|&q| distance_to_polygon(q, &p.outline).powi(2))
        .sum::<f64>()
        / outline_image.len() as f64)
        .sqrt();
    let tpl_area = template.mask.iter().filter(|&&m| m).count().max(1);
    let correlation = correlation_over(
        &images.peak,
        &template.images.peak,
        mask.iter().zip(&template.mask).map(|(a, b)| *a || *b),
    );
    let affine = if kind == MapKept::Identity {
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    } else {
        composed(t, &correction)
    };
    let det = affine[0][0] * affine[1][1] - affine[0][1] * affine[1][0];
    Ok(Registration {
        mask_xor_pct: 100.0 * s.xor(&mask) as f64 / tpl_area as f64,
        images,
        mask,
        turn_deg: (affine[1][0] - affine[0][1])
            .atan2(affine[0][0] + affine[1][1])
            .to_degrees(),
        scale: det.abs().sqrt(),
        affine,
        fallback,
        kept: kind,
        residual_sensels,
        correlation,
    })
}

/// The first of the warp and the rigid map (`[rigid, warped]`) whose footprint overlaps the
/// template's with at most `xor_identity` sensels in exactly one of them.
fn first_overlapping(
    s: &Sampler<'_>,
    [rigid_at, warped_at]: [Vec<[f64; 2]>; 2],
    params: &RegisterParams,
    xor_identity: usize,
) -> Option<(MapKept, Vec<[f64; 2]>, Vec<bool>)> {
    let warp = params.refine_intensity && params.warp_spacing > 0.0;
    [(MapKept::Warp, warped_at), (MapKept::Rigid, rigid_at)]
        .into_iter()
        .filter(|(kind, _)| warp || *kind != MapKept::Warp)
        .map(|(kind, at)| {
            let mask = s.mask(&at);
            (kind, at, mask)
        })
        .find(|(_, _, mask)| s.xor(mask) <= xor_identity)
}

/// The template's outline nodes carried by the kept map: the field and the correction, plus the
/// non-rigid step's displacement (interpolated bilinearly between the sensels' own) for a warp;
/// `start` and `at` are the template sensels' images under the field and under the kept map.
fn outline_image(
    field: &CorrespondenceField,
    correction: &refine::PlaneAffine,
    template: &Template,
    (start, at): (&[[f64; 2]], &[[f64; 2]]),
    kind: MapKept,
) -> Vec<[f64; 2]> {
    if kind == MapKept::Identity {
        return template.outline.clone();
    }
    let (rows, cols) = (template.images.rows, template.images.cols);
    let moved: Vec<[f64; 2]> = field
        .apply(&template.outline)
        .into_iter()
        .map(|q| correction.apply(q))
        .collect();
    if kind != MapKept::Warp {
        return moved;
    }
    let rigid: Vec<[f64; 2]> = start.iter().map(|&q| correction.apply(q)).collect();
    let (dx, dy): (Vec<f64>, Vec<f64>) = at
        .iter()
        .zip(&rigid)
        .map(|(w, r)| (w[0] - r[0], w[1] - r[1]))
        .unzip();
    moved
        .iter()
        .zip(&template.outline)
        .map(|(m, o)| {
            let clamp = |v: f64, n: usize| v.clamp(0.0, (n - 1) as f64);
            let (x, y) = (clamp(o[0], cols), clamp(o[1], rows));
            [
                m[0] + bilinear(&dx, rows, cols, x, y),
                m[1] + bilinear(&dy, rows, cols, x, y),
            ]
        })
        .collect()
}

/// `[M | t]` of the correction after the match's map.
fn composed(t: &Affine, correction: &refine::PlaneAffine) -> [[f64; 3]; 2] {
    let (cm, cb) = correction.as_linear();
    let (m0, t0) = (t.m, t.t);
    let mut out = [[0.0; 3]; 2];
    for (r, row) in cm.iter().enumerate() {
        out[r][0] = row[0] * m0[0][0] + row[1] * m0[1][0];
        out[r][1] = row[0] * m0[0][1] + row[1] * m0[1][1];
        out[r][2] = row[0] * t0[0] + row[1] * t0[1] + cb[r];
    }
    out
}

/// Pearson correlation of `a` and `b` (NaN read as 0) over the sensels `keep` selects; `None`
/// when fewer than 2 are kept or either is constant there.
pub fn correlation_over(a: &[f64], b: &[f64], keep: impl Iterator<Item = bool>) -> Option<f64> {
    let z = |v: f64| if v.is_nan() { 0.0 } else { v };
    let pts: Vec<(f64, f64)> = a
        .iter()
        .zip(b)
        .zip(keep)
        .filter(|(_, k)| *k)
        .map(|((&x, &y), _)| (z(x), z(y)))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in pts {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx).powi(2);
        syy += (y - my).powi(2);
    }
    let r = sxy / (sxx * syy).sqrt();
    r.is_finite().then_some(r)
}
