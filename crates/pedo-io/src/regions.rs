//! Anatomical regions of one footprint, found automatically from its image, and the measures of
//! a recording per region (docs/measures.md, "Regions").
//!
//! [`foot_axis`] finds the foot's long axis (the principal axis of the footprint's area), which
//! end is the heel (the centre of pressure moves heel → toe during stance; without a path, the
//! wider end is the forefoot) and which side is medial (the midfoot's contact lies lateral of
//! the line joining heel and forefoot, under the lateral longitudinal arch; the hallux, the
//! most loaded toe, lies medial). [`automatic_masks`] divides the footprint along that axis by
//! percentages of its length:
//!
//! * [`RegionRule::Coarse`]: the toes distal to 81 % of the foot length (the distal bound of the
//!   forefoot in the traditional percentage mask, Forghany et al. 2018), the rest in three
//!   equal thirds, hindfoot, midfoot and forefoot (Cavanagh & Rodgers 1987, the thirds of the
//!   arch index);
//! * [`RegionRule::Fine`]: the same bands, the hindfoot split into medial and lateral heel at
//!   the middle of its width, the forefoot band into the first, second and lateral (third to
//!   fifth) metatarsal heads at 35 % and 55 % of its width from the medial edge, and the toes
//!   into the hallux (medial 40 % of their width) and the lesser toes.
//!
//! Every sensel of the footprint lies in exactly one region ([`RegionMasks::labels`]).
//! [`RegionSeries`] measures a recording's frames per region (a second pass over the frames,
//! once the masks are known from the whole recording).

use crate::error::{IoError, Result};
use crate::measures::{ForceContact, Measures};
use crate::recording::Recording;

/// The regions of the coarse rule, heel to toe.
pub const COARSE_REGIONS: [&str; 4] = ["hindfoot", "midfoot", "forefoot", "toes"];

/// The regions of the fine rule.
pub const FINE_REGIONS: [&str; 8] = [
    "heel_medial",
    "heel_lateral",
    "midfoot",
    "mh1",
    "mh2",
    "mh3_5",
    "hallux",
    "lesser_toes",
];

/// Fractions of the foot length (heel end 0, toe end 1) where the hindfoot, midfoot and forefoot
/// end: the length proximal to the toes (81 %, Forghany et al. 2018's traditional forefoot
/// bound) in equal thirds (Cavanagh & Rodgers 1987).
pub const LENGTH_BOUNDS: [f64; 3] = [0.27, 0.54, 0.81];

/// Fractions of the forefoot band's width, from its medial edge, where the first and the second
/// metatarsal heads end.
pub const METATARSAL_BOUNDS: [f64; 2] = [0.35, 0.55];

/// The fraction of the toe band's width, from its medial edge, where the hallux ends.
pub const HALLUX_BOUND: f64 = 0.4;

/// The fewest sensels a footprint needs to be divided.
pub const MIN_FOOTPRINT_SENSELS: usize = 12;

/// How a footprint is divided into regions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegionRule {
    /// Hindfoot, midfoot, forefoot, toes ([`COARSE_REGIONS`]).
    Coarse,
    /// Medial and lateral heel, midfoot, first, second and lateral metatarsal heads, hallux,
    /// lesser toes ([`FINE_REGIONS`]).
    Fine,
}

impl RegionRule {
    /// The names of the rule's regions, in label order (label `k` is `names()[k - 1]`).
    pub fn names(self) -> &'static [&'static str] {
        match self {
            RegionRule::Coarse => &COARSE_REGIONS,
            RegionRule::Fine => &FINE_REGIONS,
        }
    }

    /// `"coarse"` or `"fine"`.
    pub fn name(self) -> &'static str {
        match self {
            RegionRule::Coarse => "coarse",
            RegionRule::Fine => "fine",
        }
    }
}

/// Which foot a footprint is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// A left foot.
    Left,
    /// A right foot.
    Right,
}

impl Side {
    /// `"left"` or `"right"`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// What told the heel from the toes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeelToeCue {
    /// The centre of pressure's progression along the axis over the frames in contact.
    CopPath,
    /// The footprint's shape: the distal third (forefoot and toes) is wider than the proximal
    /// one (heel).
    Shape,
    /// The sensor's layout: an insole's toe end is known (a pedar insole's row 0).
    Layout,
}

impl HeelToeCue {
    /// `"cop_path"` or `"shape"`.
    pub fn name(self) -> &'static str {
        match self {
            HeelToeCue::CopPath => "cop_path",
            HeelToeCue::Shape => "shape",
            HeelToeCue::Layout => "layout",
        }
    }
}

/// The foot's frame in the image: positions in mm, `x` along the columns and `y` along the
/// rows (sensel centres at `(column × dx, row × dy)`).
#[derive(Debug, Clone, PartialEq)]
pub struct FootAxis {
    /// The footprint's centroid (mm).
    pub centre: [f64; 2],
    /// Unit vector along the foot's axis, heel → toe.
    pub direction: [f64; 2],
    /// Unit vector across the axis, lateral → medial.
    pub medial: [f64; 2],
    /// The heel end of the footprint on the axis (mm).
    pub heel: [f64; 2],
    /// The toe end of the footprint on the axis (mm).
    pub toe: [f64; 2],
    /// The foot's length along its axis, between the outermost sensel centres (mm).
    pub length: f64,
    /// Left or right foot, as the MUN104 templates lie: a left foot with its toes towards
    /// larger rows has its hallux towards larger columns. An image seen from the other face
    /// of the sensor (as Tekscan's F-Scan insoles are) names the other foot; the masks do not
    /// depend on the name, only on the medial side found.
    pub side: Side,
    /// What told the heel from the toes.
    pub heel_toe_cue: HeelToeCue,
}

/// The regions of a footprint: one label per sensel.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionMasks {
    /// Rows of the image.
    pub rows: usize,
    /// Columns of the image.
    pub cols: usize,
    /// Per sensel (row-major) 0 outside the footprint, else the region's number `k ≥ 1`, named
    /// `names[k - 1]`.
    pub labels: Vec<u8>,
    /// The regions' names, in label order.
    pub names: Vec<String>,
    /// The rule that made them (`None` for a user's masks).
    pub rule: Option<RegionRule>,
    /// The foot's frame the automatic rules used (of a single footprint; see
    /// [`foot_axes`](Self::foot_axes) for a recording of both feet apart).
    pub axis: Option<FootAxis>,
    /// For a recording of both feet apart ([`Recording::feet`]), the foot of each region, in
    /// label order (one per name): each foot has regions of its own. Empty for one footprint.
    pub sides: Vec<Side>,
    /// For a recording of both feet apart divided by a rule, each foot's frame.
    pub foot_axes: Vec<(Side, FootAxis)>,
}

impl RegionMasks {
    /// The number of sensels of region `k` (1-based label).
    pub fn count(&self, k: u8) -> usize {
        self.labels.iter().filter(|&&l| l == k).count()
    }

    /// The foot of region `k` (1-based label), `None` for a single footprint's.
    pub fn side_of(&self, k: u8) -> Option<Side> {
        self.sides.get(usize::from(k).checked_sub(1)?).copied()
    }

    /// The masks divided per foot of `feet` (a recording of both feet apart): each region split
    /// into its part on each foot, the parts holding no sensel left out, the left foot's first.
    /// Unchanged without feet, or when already divided.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when the parts number more than 255.
    pub fn per_foot(self, feet: &[crate::recording::FootColumns]) -> Result<Self> {
        if feet.is_empty() || !self.sides.is_empty() {
            return Ok(self);
        }
        let mut out = Self {
            labels: vec![0; self.labels.len()],
            names: Vec::new(),
            sides: Vec::new(),
            foot_axes: Vec::new(),
            ..self.clone()
        };
        let mut feet: Vec<_> = feet.iter().collect();
        feet.sort_by_key(|f| f.side != Side::Left);
        for foot in feet {
            for (k, name) in self.names.iter().enumerate() {
                let on_foot = |i: usize| {
                    usize::from(self.labels[i]) == k + 1 && foot.columns.contains(&(i % self.cols))
                };
                let cells: Vec<usize> = (0..self.labels.len()).filter(|&i| on_foot(i)).collect();
                if cells.is_empty() {
                    continue;
                }
                let label = u8::try_from(out.names.len() + 1)
                    .map_err(|_| IoError::invalid("more than 255 regions over both feet"))?;
                for i in cells {
                    out.labels[i] = label;
                }
                out.names.push(name.clone());
                out.sides.push(foot.side);
            }
        }
        Ok(out)
    }
}

/// The sensels of the footprint: those whose value is finite and above 0.
fn footprint(image: &[f64]) -> Vec<usize> {
    (0..image.len())
        .filter(|&i| image[i].is_finite() && image[i] > 0.0)
        .collect()
}

fn check_image(image: &[f64], rows: usize, cols: usize, pitch: [f64; 2]) -> Result<()> {
    if rows.checked_mul(cols) != Some(image.len()) {
        return Err(IoError::invalid(format!(
            "an image of {rows}x{cols} needs {} values, got {}",
            rows.saturating_mul(cols),
            image.len()
        )));
    }
    if !(pitch.iter().all(|p| p.is_finite() && *p > 0.0)) {
        return Err(IoError::invalid(format!(
            "sensel pitch {}x{} mm is not positive",
            pitch[0], pitch[1]
        )));
    }
    Ok(())
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The foot's frame of the footprint `image` (`rows × cols`, row-major; the footprint is every
/// sensel with a finite value above 0, the values weigh the hallux cue: a peak-pressure image
/// with the sensels never in contact at 0), sensels `pitch = [dx, dy]` mm apart, and, when
/// known, the centre of pressure of each frame in sensels (`(column, row)`, `None` for a frame
/// without contact), in order.
///
/// The axis is the principal axis of the footprint's sensel centres (the eigenvector of the
/// largest eigenvalue of their covariance). The heel is the end the centre of pressure leaves
/// (its displacement along the axis, summed over consecutive frames in contact, exceeds a fifth
/// of the foot length); without such a path, the end whose third of the length is narrower.
/// The medial side is the one the hallux lies on and the midfoot's contact lies away from:
/// the sum of the toe band's pressure-weighted centroid and the opposite of the midfoot band's
/// centroid, across the axis, each relative to the middle of the heel and forefoot bands.
///
/// # Errors
///
/// [`IoError::NoObject`] when the image holds no footprint; [`IoError::InvalidInput`] when it is
/// not `rows × cols`, the pitch is not positive, or the footprint has fewer than
/// [`MIN_FOOTPRINT_SENSELS`] sensels or no length.
pub fn foot_axis(
    image: &[f64],
    rows: usize,
    cols: usize,
    pitch: [f64; 2],
    cop: Option<&[Option<[f64; 2]>]>,
) -> Result<FootAxis> {
    axis_facing(image, rows, cols, pitch, cop, None)
}

/// A foot whose side is known, and the direction (in the image, mm) its medial side faces:
/// one insole of a pair, whose medial side faces the other insole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Facing {
    /// Which foot.
    pub side: Side,
    /// A direction the medial side faces (its component across the foot's axis counts).
    pub medial: [f64; 2],
    /// A direction the toes lie in from the heel, when the sensor's layout tells (its
    /// component along the foot's axis counts).
    pub toes: Option<[f64; 2]>,
}

/// [`foot_axis`], the medial side and the foot's name taken from `facing` when given rather
/// than from the footprint's shape.
fn axis_facing(
    image: &[f64],
    rows: usize,
    cols: usize,
    pitch: [f64; 2],
    cop: Option<&[Option<[f64; 2]>]>,
    facing: Option<Facing>,
) -> Result<FootAxis> {
    check_image(image, rows, cols, pitch)?;
    let fp = footprint(image);
    if fp.is_empty() {
        return Err(IoError::no_object(
            "the image holds no footprint (no sensel above 0) to divide into regions",
        ));
    }
    if fp.len() < MIN_FOOTPRINT_SENSELS {
        return Err(IoError::invalid(format!(
            "a footprint of {} is too small to divide into regions (at least {MIN_FOOTPRINT_SENSELS})",
            crate::counted(fp.len(), "sensel")
        )));
    }
    let sensels = FootprintSensels {
        pos: (fp.iter())
            .map(|&i| [(i % cols) as f64 * pitch[0], (i / cols) as f64 * pitch[1]])
            .collect(),
        value: fp.iter().map(|&i| image[i]).collect(),
    };
    let (c, axis) = sensels.principal_axis();
    let (lo, length) = sensels.extent(c, axis);
    if length.is_nan() || length <= 0.0 {
        return Err(IoError::invalid(
            "the footprint has no length to divide into regions",
        ));
    }
    // Heel → toe: the sensor's layout, else the centre of pressure's path, else the shape.
    let forward = cop.map_or(0.0, |path| {
        path.windows(2)
            .filter_map(|w| match (w[0], w[1]) {
                (Some(a), Some(b)) => {
                    let d = [(b[0] - a[0]) * pitch[0], (b[1] - a[1]) * pitch[1]];
                    Some(dot(d, axis))
                }
                _ => None,
            })
            .sum::<f64>()
    });
    let (toward_toes, cue) = if let Some(t) = facing.and_then(|f| f.toes) {
        (dot(t, axis) >= 0.0, HeelToeCue::Layout)
    } else if forward.abs() > 0.2 * length {
        (forward >= 0.0, HeelToeCue::CopPath)
    } else {
        let step = pitch[0].min(pitch[1]);
        (
            !sensels.wider_start(c, axis, lo, length, step),
            HeelToeCue::Shape,
        )
    };
    let u = if toward_toes {
        axis
    } else {
        [-axis[0], -axis[1]]
    };
    let t0 = sensels.extent(c, u).0;
    let n_perp = [-u[1], u[0]];
    // Medial along +n_perp when the score is positive. With (x, y) = (column, row), MUN104's
    // left template (toes towards +y) has its hallux towards +x, i.e. along −n_perp. The side
    // told overrides the shape's cue (an insole's midfoot is loaded across its width, so that
    // cue is weak there).
    let score = match facing {
        Some(f) => dot(f.medial, n_perp),
        None => sensels.medial_score(c, u, t0, length),
    };
    let (medial, side) = if score >= 0.0 {
        (n_perp, Side::Right)
    } else {
        ([-n_perp[0], -n_perp[1]], Side::Left)
    };
    let heel = [c[0] + u[0] * t0, c[1] + u[1] * t0];
    let toe = [heel[0] + u[0] * length, heel[1] + u[1] * length];
    Ok(FootAxis {
        centre: c,
        direction: u,
        medial,
        heel,
        toe,
        length,
        side: facing.map_or(side, |f| f.side),
        heel_toe_cue: cue,
    })
}

/// A footprint's sensels: their centres (in the pitch's units) and values.
struct FootprintSensels {
    pos: Vec<[f64; 2]>,
    value: Vec<f64>,
}

impl FootprintSensels {
    /// The centroid and the unit principal axis (either sign) of the sensels' centres.
    fn principal_axis(&self) -> ([f64; 2], [f64; 2]) {
        let n = self.pos.len() as f64;
        let mut c = [0.0; 2];
        for p in &self.pos {
            c[0] += p[0] / n;
            c[1] += p[1] / n;
        }
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for p in &self.pos {
            let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
        }
        // The principal axis of a symmetric 2 × 2 matrix: angle ½ atan2(2 sxy, sxx − syy).
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        (c, [angle.cos(), angle.sin()])
    }

    /// The sensels' lowest position along `u` from `c`, and their extent along it.
    fn extent(&self, c: [f64; 2], u: [f64; 2]) -> (f64, f64) {
        let (lo, hi) = (self.pos.iter())
            .map(|&p| dot(sub(p, c), u))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
                (lo.min(t), hi.max(t))
            });
        (lo, hi - lo)
    }

    /// Whether the widest slice (`step` thick) of the start third along `u` (from `lo`, over
    /// `length`) is wider across the axis than the end third's: the start is then the forefoot.
    fn wider_start(&self, c: [f64; 2], u: [f64; 2], lo: f64, length: f64, step: f64) -> bool {
        let w = [-u[1], u[0]];
        let slices = ((length / 3.0) / step).ceil().max(1.0) as usize;
        let mut widths = [
            vec![(f64::INFINITY, f64::NEG_INFINITY); slices],
            vec![(f64::INFINITY, f64::NEG_INFINITY); slices],
        ];
        for &p in &self.pos {
            let f = dot(sub(p, c), u) - lo;
            let end = if f <= length / 3.0 {
                0
            } else if f >= 2.0 * length / 3.0 {
                1
            } else {
                continue;
            };
            let from_end = if end == 0 { f } else { length - f };
            let s = ((from_end / step) as usize).min(slices - 1);
            let v = dot(sub(p, c), w);
            let (a, b) = widths[end][s];
            widths[end][s] = (a.min(v), b.max(v));
        }
        let widest = |ws: &[(f64, f64)]| {
            ws.iter()
                .filter(|(a, b)| a <= b)
                .map(|(a, b)| b - a)
                .fold(0.0, f64::max)
        };
        widest(&widths[0]) > widest(&widths[1])
    }

    /// The shape's cue for the medial side along `[-u[1], u[0]]` (positive: that way), the
    /// heel at `t0` along `u` from `c`: the toes' pressure-weighted offset across the axis, less
    /// the midfoot's, each from the middle of the heel's and the forefoot's widths (the
    /// [`LENGTH_BOUNDS`] bands).
    fn medial_score(&self, c: [f64; 2], u: [f64; 2], t0: f64, length: f64) -> f64 {
        let n_perp = [-u[1], u[0]];
        let band = |f: f64| -> usize {
            LENGTH_BOUNDS
                .iter()
                .position(|&b| f < b)
                .unwrap_or(LENGTH_BOUNDS.len())
        };
        let mut ext = [(f64::INFINITY, f64::NEG_INFINITY); 4];
        let (mut mid_sum, mut mid_n) = (0.0, 0.0);
        let (mut toe_sum, mut toe_w) = (0.0, 0.0);
        for (&p, &value) in self.pos.iter().zip(&self.value) {
            let b = band((dot(sub(p, c), u) - t0) / length);
            let v = dot(sub(p, c), n_perp);
            ext[b] = (ext[b].0.min(v), ext[b].1.max(v));
            if b == 1 {
                mid_sum += v;
                mid_n += 1.0;
            } else if b == 3 {
                toe_sum += v * value;
                toe_w += value;
            }
        }
        let centre_of = |e: (f64, f64)| (e.0 <= e.1).then_some(0.5 * (e.0 + e.1));
        let reference = match (centre_of(ext[0]), centre_of(ext[2])) {
            (Some(a), Some(b)) => 0.5 * (a + b),
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => 0.0,
        };
        let mut score = 0.0;
        if toe_w > 0.0 {
            score += toe_sum / toe_w - reference;
        }
        if mid_n > 0.0 {
            score -= mid_sum / mid_n - reference;
        }
        score
    }
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// The regions of the footprint `image` by `rule` (see [`foot_axis`] for the arguments and the
/// axis; the module for the rules): every sensel of the footprint labelled with exactly one
/// region, the others 0.
///
/// # Errors
///
/// Those of [`foot_axis`].
pub fn automatic_masks(
    image: &[f64],
    rows: usize,
    cols: usize,
    pitch: [f64; 2],
    cop: Option<&[Option<[f64; 2]>]>,
    rule: RegionRule,
) -> Result<RegionMasks> {
    masks_facing(image, rows, cols, pitch, cop, rule, None)
}

/// [`automatic_masks`] of a foot `facing` a known way (see [`axis_facing`]).
fn masks_facing(
    image: &[f64],
    rows: usize,
    cols: usize,
    pitch: [f64; 2],
    cop: Option<&[Option<[f64; 2]>]>,
    rule: RegionRule,
    facing: Option<Facing>,
) -> Result<RegionMasks> {
    let axis = axis_facing(image, rows, cols, pitch, cop, facing)?;
    let fp = footprint(image);
    let pos = |i: usize| [(i % cols) as f64 * pitch[0], (i / cols) as f64 * pitch[1]];
    let bands: Vec<usize> = fp
        .iter()
        .map(|&i| {
            let f = dot(sub(pos(i), axis.heel), axis.direction) / axis.length;
            LENGTH_BOUNDS
                .iter()
                .position(|&b| f < b)
                .unwrap_or(LENGTH_BOUNDS.len())
        })
        .collect();
    // Position across the axis, from the medial edge of each band (0) to its lateral edge (1).
    let across: Vec<f64> = fp
        .iter()
        .map(|&i| dot(sub(pos(i), axis.centre), axis.medial))
        .collect();
    let mut ext = [(f64::INFINITY, f64::NEG_INFINITY); 4];
    for (k, &b) in bands.iter().enumerate() {
        ext[b] = (ext[b].0.min(across[k]), ext[b].1.max(across[k]));
    }
    let from_medial = |k: usize| {
        let (lo, hi) = ext[bands[k]];
        if hi > lo {
            (hi - across[k]) / (hi - lo)
        } else {
            0.5
        }
    };
    let mut labels = vec![0u8; image.len()];
    for (k, &i) in fp.iter().enumerate() {
        let b = bands[k];
        let label = match rule {
            RegionRule::Coarse => b + 1,
            RegionRule::Fine => {
                let w = from_medial(k);
                match b {
                    0 => {
                        if w < 0.5 {
                            1
                        } else {
                            2
                        }
                    }
                    1 => 3,
                    2 => {
                        if w < METATARSAL_BOUNDS[0] {
                            4
                        } else if w < METATARSAL_BOUNDS[1] {
                            5
                        } else {
                            6
                        }
                    }
                    _ => {
                        if w < HALLUX_BOUND {
                            7
                        } else {
                            8
                        }
                    }
                }
            }
        };
        labels[i] = label as u8;
    }
    Ok(RegionMasks {
        rows,
        cols,
        labels,
        names: rule.names().iter().map(|s| s.to_string()).collect(),
        rule: Some(rule),
        axis: Some(axis),
        sides: Vec::new(),
        foot_axes: Vec::new(),
    })
}

/// The measures of one region of a recording (docs/measures.md), in the units of the
/// recording's [`Measures`].
#[derive(Debug, Clone, PartialEq)]
pub struct RegionValues {
    /// The region's name.
    pub name: String,
    /// Its sensels.
    pub sensels: usize,
    /// The largest value of the peak image over the region.
    pub peak_pressure: f64,
    /// The largest value of the PTI image over the region.
    pub pti_max: f64,
    /// The largest force (load) of the region in a frame.
    pub peak_force: f64,
    /// `Σ F·Δt` of the region's force.
    pub fti: f64,
    /// The largest number of the region's sensels loaded in a frame × sensel area.
    pub max_contact_area: f64,
    /// `(last − first + 1) × Δt` of the frames whose region force exceeds its own
    /// `min + 10 % × (max − min)`; 0 for a region never loaded.
    pub contact_time: f64,
    /// The region's share of the footprint's force-time integral (%).
    pub impulse_share: f64,
    /// Its force and peak pressure over each stance of the recording's [`Measures`] (in their
    /// order), resampled to 0–100 % of contact as the stance's own curves
    /// ([`crate::stances::resample`]); empty for a region carried by the field. A foot's region
    /// has those of its foot's stances ([`crate::measures::FootMeasures`]).
    pub curves: Vec<RegionCurves>,
    /// The foot it lies on, for a recording of both feet apart ([`RegionMasks::sides`]); its
    /// `impulse_share` is then of that foot's impulse.
    pub foot: Option<Side>,
}

/// One region's curves over one stance, at [`CURVE_POINTS`](crate::stances::CURVE_POINTS)
/// points of its contact, in the units of the recording's [`Measures`].
#[derive(Debug, Clone, PartialEq)]
pub struct RegionCurves {
    /// The region's force (or load): its loaded sensels' load, as the frames' force.
    pub force: Vec<f64>,
    /// The largest value at one of the region's sensels, as the frames' peak pressure.
    pub peak_pressure: Vec<f64>,
}

/// The per-frame force and contact of each region of `masks` over a recording's frames, fed
/// one frame at a time ([`add_frame`](Self::add_frame)); [`finish`](Self::finish) with the
/// recording's [`Measures`] (the same frames and threshold) gives each region's values.
#[derive(Debug, Clone)]
pub struct RegionSeries {
    labels: Vec<u8>,
    names: Vec<String>,
    /// The foot of each region ([`RegionMasks::sides`]).
    sides: Vec<Side>,
    mask: Vec<bool>,
    threshold: f64,
    force_factor: f64,
    /// File units → the measures' pressure unit.
    pressure_factor: f64,
    area: f64,
    dt: f64,
    /// Per region, its force in each frame.
    forces: Vec<Vec<f64>>,
    /// Per region, its largest value (file units) in each frame.
    peaks: Vec<Vec<f64>>,
    contact: Vec<usize>,
}

impl RegionSeries {
    /// Starts the series of `masks` over frames of `recording` (its mask, pitch, rate and
    /// units), a sensel loaded above 0 and at or above `threshold` (file units), as
    /// [`RecordingMeasures`](crate::measures::RecordingMeasures) counts it.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when the masks are not the recording's size, have more than
    /// 255 regions or a label without a name, or `threshold` is not finite.
    pub fn new(recording: &Recording, threshold: f64, masks: &RegionMasks) -> Result<Self> {
        if masks.rows != recording.rows() || masks.cols != recording.cols() {
            return Err(IoError::invalid(format!(
                "region masks of {}x{} do not fit frames of {}x{}",
                masks.rows,
                masks.cols,
                recording.rows(),
                recording.cols()
            )));
        }
        if masks.labels.len() != masks.rows * masks.cols {
            return Err(IoError::invalid("region masks hold one label per sensel"));
        }
        if let Some(&l) = masks
            .labels
            .iter()
            .find(|&&l| usize::from(l) > masks.names.len())
        {
            return Err(IoError::invalid(format!(
                "region label {l} has no name ({} named)",
                masks.names.len()
            )));
        }
        if !threshold.is_finite() {
            return Err(IoError::invalid(format!(
                "contact threshold {threshold} is not finite"
            )));
        }
        let area = recording.sensel_area();
        Ok(Self {
            labels: masks.labels.clone(),
            names: masks.names.clone(),
            sides: masks.sides.clone(),
            mask: recording.sensor_mask().to_vec(),
            threshold,
            force_factor: recording.force_factor().unwrap_or(area.unwrap_or(1.0)),
            pressure_factor: crate::recording::kpa_per_unit(&recording.units).unwrap_or(1.0),
            area: area.unwrap_or(1.0),
            dt: recording.dt_s.unwrap_or(1.0),
            forces: vec![Vec::new(); masks.names.len()],
            peaks: vec![Vec::new(); masks.names.len()],
            contact: vec![0; masks.names.len()],
        })
    }

    /// Adds the next frame (`rows × cols` values in the file's units).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `values` is not `rows × cols` long.
    pub fn add_frame(&mut self, values: &[f32]) -> Result<()> {
        if values.len() != self.labels.len() {
            return Err(IoError::invalid(format!(
                "a frame needs {} values, got {}",
                self.labels.len(),
                values.len()
            )));
        }
        let r = self.names.len();
        let mut load = vec![0.0f64; r];
        let mut count = vec![0usize; r];
        let mut top = vec![0.0f64; r];
        for (i, &v) in values.iter().enumerate() {
            let l = self.labels[i];
            if l == 0 || !self.mask[i] {
                continue;
            }
            let v = f64::from(v);
            // Every value counts in the peak, as in the frames' peak pressure.
            let t = &mut top[usize::from(l) - 1];
            if v > *t {
                *t = v;
            }
            if v > 0.0 && v >= self.threshold {
                load[usize::from(l) - 1] += v;
                count[usize::from(l) - 1] += 1;
            }
        }
        for (((f, c), l), n) in (self.forces.iter_mut().zip(&mut self.contact))
            .zip(&load)
            .zip(&count)
        {
            f.push(l * self.force_factor);
            *c = (*c).max(*n);
        }
        for (p, t) in self.peaks.iter_mut().zip(top) {
            p.push(t);
        }
        Ok(())
    }

    /// Each region's values, with the images of `measures` (those of the same frames).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when no frame was added, the images are not the masks' size,
    /// the frames added are not those of `measures`, or no region holds any load (the
    /// footprint's impulse is 0).
    pub fn finish(self, measures: &Measures) -> Result<Vec<RegionValues>> {
        let n = self.forces.first().map_or(0, Vec::len);
        if n == 0 {
            return Err(IoError::invalid("no frame to measure per region"));
        }
        if n != measures.frames.len() {
            return Err(IoError::invalid(format!(
                "{} measured per region, the measures hold {}",
                crate::counted(n, "frame"),
                measures.frames.len()
            )));
        }
        if measures.peak.len() != self.labels.len() {
            return Err(IoError::invalid(
                "the measures' images do not fit the region masks",
            ));
        }
        let ftis: Vec<f64> = self
            .forces
            .iter()
            .map(|f| f.iter().sum::<f64>() * self.dt)
            .collect();
        let total: f64 = ftis.iter().sum();
        if total.is_nan() || total <= 0.0 {
            return Err(IoError::invalid(
                "no region is loaded in any frame: the regions have no impulse to share",
            ));
        }
        // A foot's regions share its own impulse.
        let foot_total = |side: Side| -> f64 {
            (ftis.iter().zip(&self.sides))
                .filter(|&(_, &s)| s == side)
                .map(|(f, _)| f)
                .sum()
        };
        let mut out = Vec::with_capacity(self.names.len());
        for (k, name) in self.names.iter().enumerate() {
            let foot = self.sides.get(k).copied();
            let (total, own) = match foot {
                Some(side) => (
                    foot_total(side),
                    (measures.feet.iter())
                        .find(|f| f.side == side)
                        .map(|f| &f.measures),
                ),
                None => (total, Some(measures)),
            };
            let label = (k + 1) as u8;
            let (mut peak, mut pti, mut sensels) = (0.0f64, 0.0f64, 0usize);
            for (i, &l) in self.labels.iter().enumerate() {
                if l == label && self.mask[i] {
                    sensels += 1;
                    if measures.peak[i].is_finite() {
                        peak = peak.max(measures.peak[i]);
                    }
                    if measures.pti[i].is_finite() {
                        pti = pti.max(measures.pti[i]);
                    }
                }
            }
            let contact = ForceContact::of(&self.forces[k]);
            let (hi, contact_time) = (contact.peak, contact.time(self.dt));
            out.push(RegionValues {
                name: name.clone(),
                sensels,
                peak_pressure: peak,
                pti_max: pti,
                peak_force: hi,
                fti: ftis[k],
                max_contact_area: self.contact[k] as f64 * self.area,
                contact_time,
                impulse_share: if total > 0.0 {
                    100.0 * ftis[k] / total
                } else {
                    0.0
                },
                curves: own.map_or_else(Vec::new, |m| self.stance_curves(k, m)),
                foot,
            });
        }
        Ok(out)
    }
}

impl RegionSeries {
    /// Region `k`'s force and peak pressure over each stance of `measures` (whose frames are
    /// those added, the first added being `measures.frames.start`).
    fn stance_curves(&self, k: usize, measures: &Measures) -> Vec<RegionCurves> {
        let start = measures.frames.start;
        let curve = |v: &[f64], factor: f64| -> Vec<f64> {
            let known: Vec<Option<f64>> = v.iter().map(|x| Some(x * factor)).collect();
            crate::stances::resample(&known)
                .into_iter()
                .flatten()
                .collect()
        };
        measures
            .stances
            .iter()
            .map(|s| {
                let frames = (s.stance.first - start)..(s.stance.last - start + 1);
                RegionCurves {
                    force: curve(&self.forces[k][frames.clone()], 1.0),
                    peak_pressure: curve(&self.peaks[k][frames], self.pressure_factor),
                }
            })
            .collect()
    }
}

/// The per-frame force and contact of regions whose sensels change from frame to frame (regions
/// that move with the foot, followed through the stance): fed one frame at a time with each
/// region's sensels on it ([`add_frame`](Self::add_frame)); [`finish`](Self::finish) gives each
/// region's values as [`RegionSeries`] does for fixed ones, the images' values (peak pressure,
/// PTI) taken per sensel over the frames it lies in the region only.
#[derive(Debug, Clone)]
pub struct MovingRegionSeries {
    names: Vec<String>,
    mask: Vec<bool>,
    threshold: f64,
    force_factor: f64,
    pressure_factor: f64,
    area: f64,
    dt: f64,
    forces: Vec<Vec<f64>>,
    contact: Vec<f64>,
    sensels: Vec<f64>,
    peak: Vec<f64>,
    /// Per region, per sensel, the sum of its loaded values over the frames it lay in the region.
    sums: Vec<Vec<f64>>,
}

impl MovingRegionSeries {
    /// Starts the series of the regions `names` over frames of `recording` (its mask, pitch,
    /// rate and units), a sensel loaded above 0 and at or above `threshold` (file units).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `threshold` is not finite.
    pub fn new(recording: &Recording, threshold: f64, names: &[String]) -> Result<Self> {
        if !threshold.is_finite() {
            return Err(IoError::invalid(format!(
                "contact threshold {threshold} is not finite"
            )));
        }
        let area = recording.sensel_area();
        let n = recording.rows() * recording.cols();
        Ok(Self {
            names: names.to_vec(),
            mask: recording.sensor_mask().to_vec(),
            threshold,
            force_factor: recording.force_factor().unwrap_or(area.unwrap_or(1.0)),
            pressure_factor: crate::recording::kpa_per_unit(&recording.units).unwrap_or(1.0),
            area: area.unwrap_or(1.0),
            dt: recording.dt_s.unwrap_or(1.0),
            forces: vec![Vec::new(); names.len()],
            contact: vec![0.0; names.len()],
            sensels: vec![0.0; names.len()],
            peak: vec![0.0; names.len()],
            sums: vec![vec![0.0; n]; names.len()],
        })
    }

    /// Adds the next frame (`rows × cols` values in the file's units) with the share of each
    /// sensel each region covers on it (row-major, 0..=1; `None`: the region is not on this
    /// frame, its force 0): a sensel counts towards a region's force, contact and PTI by its
    /// share, towards its peak pressure when at least half of it is inside.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `values` or a region's shares are not `rows × cols`
    /// long, or `shares` does not hold one entry per region.
    pub fn add_frame(&mut self, values: &[f32], shares: &[Option<Vec<f64>>]) -> Result<()> {
        let n = self.mask.len();
        if values.len() != n || shares.len() != self.names.len() {
            return Err(IoError::invalid(format!(
                "a frame needs {n} values and the sensels of {} regions, got {} and {}",
                self.names.len(),
                values.len(),
                shares.len()
            )));
        }
        for (k, region) in shares.iter().enumerate() {
            let (mut load, mut count, mut held) = (0.0f64, 0.0f64, 0.0f64);
            if let Some(region) = region {
                if region.len() != n {
                    return Err(IoError::invalid(format!(
                        "region {} holds {} sensels' shares, the frame {n}",
                        self.names[k],
                        region.len()
                    )));
                }
                for i in (0..n).filter(|&i| region[i] > 0.0 && self.mask[i]) {
                    let w = region[i];
                    held += w;
                    let v = f64::from(values[i]);
                    if !v.is_finite() {
                        continue;
                    }
                    if w >= 0.5 {
                        self.peak[k] = self.peak[k].max(v);
                    }
                    if v > 0.0 && v >= self.threshold {
                        load += w * v;
                        count += w;
                        self.sums[k][i] += w * v;
                    }
                }
            }
            self.forces[k].push(load * self.force_factor);
            self.contact[k] = self.contact[k].max(count);
            self.sensels[k] = self.sensels[k].max(held);
        }
        Ok(())
    }

    /// Each region's values ([`RegionValues`]; `sensels` is the most it held on a frame), its
    /// share of `total_fti`, the footprint's force-time integral (that of the fixed regions,
    /// so that fixed and moving shares compare).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when no frame was added or `total_fti` is not above 0.
    pub fn finish(self, total_fti: f64) -> Result<Vec<RegionValues>> {
        let n = self.names.len();
        self.finish_each(&vec![total_fti; n], &vec![None; n])
    }

    /// Each region's values as [`finish`](Self::finish) gives them, the `k`-th region's
    /// `impulse_share` of `total_fti[k]` and its `foot` `feet[k]`: for a recording of both feet
    /// apart, each region's foot and the force-time integral of that foot's fixed regions.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when no frame was added, `total_fti` or `feet` do not hold
    /// one entry per region, or a total is not above 0.
    pub fn finish_each(
        self,
        total_fti: &[f64],
        feet: &[Option<Side>],
    ) -> Result<Vec<RegionValues>> {
        if self.forces.first().is_none_or(Vec::is_empty) {
            return Err(IoError::invalid(
                "no frame to measure the moving regions on",
            ));
        }
        if total_fti.len() != self.names.len() || feet.len() != self.names.len() {
            return Err(IoError::invalid(format!(
                "{} moving regions, {} totals and {} feet given",
                self.names.len(),
                total_fti.len(),
                feet.len()
            )));
        }
        if total_fti.iter().any(|t| t.is_nan() || *t <= 0.0) {
            return Err(IoError::invalid(
                "the footprint has no impulse for the moving regions to share",
            ));
        }
        let (k, dt) = (self.pressure_factor, self.dt);
        let mut out = Vec::with_capacity(self.names.len());
        for (r, name) in self.names.iter().enumerate() {
            let f = &self.forces[r];
            let fti = f.iter().sum::<f64>() * dt;
            let contact = ForceContact::of(f);
            let (hi, contact_time) = (contact.peak, contact.time(dt));
            out.push(RegionValues {
                name: name.clone(),
                sensels: self.sensels[r].round() as usize,
                peak_pressure: self.peak[r] * k,
                pti_max: self.sums[r].iter().fold(0.0f64, |m, &s| m.max(s)) * k * dt,
                peak_force: hi,
                fti,
                max_contact_area: self.contact[r] * self.area,
                contact_time,
                impulse_share: 100.0 * fti / total_fti[r],
                // The stance-normalised curves are the fixed regions' (`curves.csv`).
                curves: Vec::new(),
                foot: feet[r],
            });
        }
        Ok(out)
    }
}

/// The automatic regions of `recording`'s frames `frames` by `rule`, and their values: the
/// footprint is every sensel loaded in some frame (its PTI above 0), weighted by its peak
/// pressure; the centre of pressure's path tells heel from toe.
///
/// # Errors
///
/// Those of [`Measures::of_recording`], [`automatic_masks`] and [`RegionSeries`].
pub fn recording_regions(
    recording: &Recording,
    threshold: f64,
    frames: std::ops::Range<usize>,
    rule: RegionRule,
) -> Result<(RegionMasks, Vec<RegionValues>)> {
    let measures = Measures::of_recording(recording, threshold, frames)?;
    regions_of_measures(recording, threshold, &measures, rule)
}

/// [`recording_regions`] of a recording whose [`Measures`] (over the frames and above the
/// `threshold` to measure the regions on) are taken already.
///
/// # Errors
///
/// Those of [`automatic_masks`] and [`RegionSeries`].
pub fn regions_of_measures(
    recording: &Recording,
    threshold: f64,
    measures: &Measures,
    rule: RegionRule,
) -> Result<(RegionMasks, Vec<RegionValues>)> {
    let cop: Vec<Option<[f64; 2]>> = recording
        .measures_of(threshold, measures.frames.clone())
        .iter()
        .map(|m| m.cop)
        .collect();
    let masks = masks_of_measures(recording, measures, Some(&cop), rule)?;
    let values = region_values(recording, threshold, &masks, measures)?;
    Ok((masks, values))
}

/// The values of each region of `masks` (automatic or the user's) over the frames of
/// `measures`, measured on `recording`'s frames above `threshold`.
///
/// # Errors
///
/// Those of [`RegionSeries`]; a frame of `measures` that `recording` does not hold.
pub fn region_values(
    recording: &Recording,
    threshold: f64,
    masks: &RegionMasks,
    measures: &Measures,
) -> Result<Vec<RegionValues>> {
    let mut series = RegionSeries::new(recording, threshold, masks)?;
    for t in measures.frames.clone() {
        let values = recording
            .frame_slice(t)
            .ok_or_else(|| IoError::invalid(format!("frame {t} is beyond the recording")))?;
        series.add_frame(&values)?;
    }
    series.finish(measures)
}

/// The automatic masks of a recording's [`Measures`]: the footprint image is the peak image
/// where the PTI is above 0 (the sensels loaded in some frame), 0 elsewhere.
///
/// # Errors
///
/// Those of [`automatic_masks`].
pub fn masks_of_measures(
    recording: &Recording,
    measures: &Measures,
    cop: Option<&[Option<[f64; 2]>]>,
    rule: RegionRule,
) -> Result<RegionMasks> {
    if !measures.feet.is_empty() {
        return feet_masks(recording, measures, rule);
    }
    let pitch = recording.pitch_mm.unwrap_or([1.0, 1.0]);
    let image = footprint_image(measures);
    automatic_masks(&image, measures.rows, measures.cols, pitch, cop, rule)
}

/// The peak image where the PTI is above 0 (the sensels loaded in some frame), 0 elsewhere.
fn footprint_image(measures: &Measures) -> Vec<f64> {
    (measures.peak.iter().zip(&measures.pti))
        .map(|(&p, &q)| if q > 0.0 { p } else { 0.0 })
        .collect()
}

/// The masks of each foot of a recording of both apart ([`Measures::feet`]), the left foot's
/// regions first: each foot's footprint divided alone, its toes towards row 0 (the pedar
/// reader's layout, the only one with both feet apart), its medial side the one facing the
/// other foot's insole (both insoles lie side by side as seen from above, so their medial sides
/// face).
fn feet_masks(recording: &Recording, measures: &Measures, rule: RegionRule) -> Result<RegionMasks> {
    let pitch = recording.pitch_mm.unwrap_or([1.0, 1.0]);
    let (rows, cols) = (measures.rows, measures.cols);
    let mut out = RegionMasks {
        rows,
        cols,
        labels: vec![0; rows * cols],
        names: Vec::new(),
        rule: Some(rule),
        axis: None,
        sides: Vec::new(),
        foot_axes: Vec::new(),
    };
    let mut feet: Vec<_> = measures.feet.iter().collect();
    feet.sort_by_key(|f| f.side != Side::Left);
    for foot in feet {
        // Row 0 is an insole's toe end (the pedar reader's layout); the centre of pressure of
        // a stance the recording cuts need not progress far enough to tell.
        let facing = Facing {
            side: foot.side,
            medial: [medial_dx(recording, &foot.columns, cols), 0.0],
            toes: Some([0.0, -1.0]),
        };
        let image = footprint_image(&foot.measures);
        let m = masks_facing(&image, rows, cols, pitch, None, rule, Some(facing))
            .map_err(|e| IoError::invalid(format!("the {} foot: {e}", foot.side.name())))?;
        let first = out.names.len() as u8;
        for (o, &l) in out.labels.iter_mut().zip(&m.labels) {
            if l > 0 {
                *o = first + l;
            }
        }
        out.sides.extend(m.names.iter().map(|_| foot.side));
        out.names.extend(m.names);
        out.foot_axes.extend(m.axis.map(|a| (foot.side, a)));
    }
    Ok(out)
}

/// Which way along the columns (+1 or −1) the medial side of the foot on `columns` faces: that
/// of the other foot's columns (or the image's middle, without another foot).
fn medial_dx(recording: &Recording, columns: &std::ops::Range<usize>, cols: usize) -> f64 {
    let middle = |r: &std::ops::Range<usize>| (r.start + r.end) as f64 / 2.0;
    let other = (recording.feet.iter())
        .find(|f| f.columns != *columns)
        .map_or(cols as f64 / 2.0, |f| middle(&f.columns));
    if other >= middle(columns) {
        1.0
    } else {
        -1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mun104(name: &str) -> (Vec<f64>, usize, usize) {
        let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(path).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
            .collect();
        let (r, c) = (rows.len(), rows[0].len());
        (rows.concat(), r, c)
    }

    /// `image` turned by `deg` about its centre (and mirrored across its columns first when
    /// `mirror`), bilinear, into a square canvas of side `side`; returns the canvas and the
    /// map of a point of the original (x = column, y = row) into it.
    /// The image `get(row, col)` read bilinearly at column `x`, row `y`.
    fn bilinear(get: &impl Fn(isize, isize) -> f64, x: f64, y: f64) -> f64 {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (c, r) = (x0 as isize, y0 as isize);
        get(r, c) * (1.0 - fx) * (1.0 - fy)
            + get(r, c + 1) * fx * (1.0 - fy)
            + get(r + 1, c) * (1.0 - fx) * fy
            + get(r + 1, c + 1) * fx * fy
    }

    fn turned(
        image: &[f64],
        rows: usize,
        cols: usize,
        deg: f64,
        mirror: bool,
        side: usize,
    ) -> (Vec<f64>, impl Fn([f64; 2]) -> [f64; 2]) {
        let (s, co) = deg.to_radians().sin_cos();
        let (cx, cy) = ((cols - 1) as f64 / 2.0, (rows - 1) as f64 / 2.0);
        let m = (side - 1) as f64 / 2.0;
        let forward = move |p: [f64; 2]| {
            let x = if mirror {
                (cols - 1) as f64 - p[0]
            } else {
                p[0]
            } - cx;
            let y = p[1] - cy;
            [m + co * x - s * y, m + s * x + co * y]
        };
        let get = |r: isize, c: isize| {
            if r < 0 || c < 0 || r >= rows as isize || c >= cols as isize {
                0.0
            } else {
                let c = if mirror { cols as isize - 1 - c } else { c };
                image[r as usize * cols + c as usize]
            }
        };
        let mut out = vec![0.0; side * side];
        for r in 0..side {
            for c in 0..side {
                // Inverse map: canvas → original (before mirroring).
                let (x, y) = (c as f64 - m, r as f64 - m);
                let (ox, oy) = (co * x + s * y + cx, -s * x + co * y + cy);
                let v = bilinear(&get, ox, oy);
                // Interpolation smears the footprint's edge: keep what is clearly loaded.
                out[r * side + c] = if v >= 1.0 { v } else { 0.0 };
            }
        }
        (out, forward)
    }

    fn centroid(masks: &RegionMasks, name: &str) -> [f64; 2] {
        let k = masks.names.iter().position(|n| n == name).unwrap() as u8 + 1;
        let (mut s, mut n) = ([0.0; 2], 0.0);
        for (i, &l) in masks.labels.iter().enumerate() {
            if l == k {
                s[0] += (i % masks.cols) as f64;
                s[1] += (i / masks.cols) as f64;
                n += 1.0;
            }
        }
        assert!(n > 0.0, "region {name} is empty");
        [s[0] / n, s[1] / n]
    }

    /// The fine and coarse regions of MUN104's templates, turned and mirrored, lie where the
    /// anatomy puts them: in the untouched left template toes are towards larger rows and the
    /// medial side towards larger columns.
    #[test]
    fn mun104_turned_and_mirrored_keeps_its_anatomy() {
        for (file, right) in [("MUN104L.csv", false), ("MUN104R.csv", true)] {
            let (img, rows, cols) = mun104(file);
            for mirror in [false, true] {
                for deg in [-30.0, -15.0, 0.0, 10.0, 30.0] {
                    let side = 80;
                    let (canvas, fwd) = turned(&img, rows, cols, deg, mirror, side);
                    let is_right = right ^ mirror;
                    let case = format!("{file} turned {deg}°, mirrored {mirror}");
                    // Unit vectors of the original's distal (+row) and medial directions in
                    // the canvas.
                    let o = fwd([0.0, 0.0]);
                    let d = sub(fwd([0.0, 1.0]), o);
                    let med_x = if right { -1.0 } else { 1.0 };
                    let md = sub(fwd([med_x, 0.0]), o);
                    for rule in [RegionRule::Coarse, RegionRule::Fine] {
                        let m = automatic_masks(&canvas, side, side, [5.0, 5.0], None, rule)
                            .unwrap_or_else(|e| panic!("{case}: {e}"));
                        // A partition of the footprint.
                        let fp = canvas.iter().filter(|&&v| v > 0.0).count();
                        let labelled = m.labels.iter().filter(|&&l| l > 0).count();
                        assert_eq!(fp, labelled, "{case}");
                        assert!(m.labels.iter().all(|&l| usize::from(l) <= m.names.len()));
                        let axis = m.axis.as_ref().unwrap();
                        assert_eq!(
                            axis.side,
                            if is_right { Side::Right } else { Side::Left },
                            "{case}"
                        );
                        let along = |n: &str| dot(centroid(&m, n), d);
                        let across = |n: &str| dot(centroid(&m, n), md);
                        match rule {
                            RegionRule::Coarse => {
                                let a: Vec<f64> =
                                    COARSE_REGIONS.iter().map(|&n| along(n)).collect();
                                assert!(a.windows(2).all(|w| w[0] < w[1]), "{case}: {a:?}");
                            }
                            RegionRule::Fine => {
                                assert!(along("heel_medial") < along("midfoot"), "{case}");
                                assert!(along("midfoot") < along("mh2"), "{case}");
                                assert!(along("mh1") < along("hallux"), "{case}");
                                assert!(along("mh3_5") < along("lesser_toes"), "{case}");
                                assert!(across("heel_medial") > across("heel_lateral"), "{case}");
                                assert!(across("mh1") > across("mh2"), "{case}");
                                assert!(across("mh2") > across("mh3_5"), "{case}");
                                assert!(across("hallux") > across("lesser_toes"), "{case}");
                            }
                        }
                    }
                }
            }
        }
    }

    /// Every frame of `rec` turned by `deg` about the centre of a `side × side` canvas
    /// (bilinear), square sensels of the recording's pitch.
    fn turned_recording(rec: &Recording, deg: f64, side: usize) -> Recording {
        let (rows, cols) = (rec.rows(), rec.cols());
        let (s, co) = deg.to_radians().sin_cos();
        let (cx, cy) = ((cols - 1) as f64 / 2.0, (rows - 1) as f64 / 2.0);
        let m = (side - 1) as f64 / 2.0;
        let mut data = Vec::with_capacity(rec.n_frames() * side * side);
        for t in 0..rec.n_frames() {
            let f = rec.frame_slice(t).unwrap();
            let get = |r: isize, c: isize| {
                if r < 0 || c < 0 || r >= rows as isize || c >= cols as isize {
                    0.0
                } else {
                    f64::from(f[r as usize * cols + c as usize])
                }
            };
            for r in 0..side {
                for c in 0..side {
                    let (x, y) = (c as f64 - m, r as f64 - m);
                    let (ox, oy) = (co * x + s * y + cx, -s * x + co * y + cy);
                    let v = bilinear(&get, ox, oy);
                    data.push(v as f32);
                }
            }
        }
        let mut out = Recording::new(rec.n_frames(), side, side, data, vec![true; side * side])
            .unwrap()
            .with_units(rec.units.clone());
        out.pitch_mm = rec.pitch_mm;
        out.dt_s = rec.dt_s;
        out
    }

    /// The real emed step of pressuRe: the regions partition the sensels ever loaded, their
    /// FTIs add up to the recording's, and their shares of the impulse move by less than 2
    /// percentage points when the whole recording is turned by 10°.
    #[test]
    fn a_real_step_s_regions_are_stable_under_a_turn() {
        let path = format!(
            "{}/../../benches/data/emed-pressuRe-step.lst",
            env!("CARGO_MANIFEST_DIR")
        );
        let rec = crate::read_recording(path).unwrap();
        let n = rec.n_frames();
        for rule in [RegionRule::Coarse, RegionRule::Fine] {
            let (masks, values) = recording_regions(&rec, 0.0, 0..n, rule).unwrap();
            let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
            let loaded = m.pti.iter().filter(|&&q| q > 0.0).count();
            assert_eq!(masks.labels.iter().filter(|&&l| l > 0).count(), loaded);
            let fti: f64 = values.iter().map(|v| v.fti).sum();
            assert!((fti - m.values.fti).abs() < 1e-9 * m.values.fti, "{fti}");
            let share: f64 = values.iter().map(|v| v.impulse_share).sum();
            assert!((share - 100.0).abs() < 1e-9);
            let peak = values.iter().map(|v| v.peak_pressure).fold(0.0, f64::max);
            assert_eq!(peak, m.values.peak_pressure);
            for v in &values {
                assert!(v.sensels > 0 && v.fti > 0.0, "{rule:?}: {v:?}");
                assert!(v.contact_time > 0.0 && v.contact_time <= m.values.contact_time + 1e-12);
                assert!(v.max_contact_area <= m.values.max_contact_area);
            }
            // A walking step: the heel is found from the centre of pressure's path.
            let axis = masks.axis.as_ref().unwrap();
            assert_eq!(axis.heel_toe_cue, HeelToeCue::CopPath);
            for deg in [-10.0, 10.0] {
                let side = 130;
                let turned = turned_recording(&rec, deg, side);
                let (tm, tv) = recording_regions(&turned, 0.0, 0..n, rule).unwrap();
                assert_eq!(tm.axis.as_ref().unwrap().side, axis.side, "{rule:?} {deg}");
                let worst = (values.iter().zip(&tv))
                    .map(|(a, b)| (a.impulse_share - b.impulse_share).abs())
                    .fold(0.0, f64::max);
                eprintln!("{rule:?} turned {deg}°: largest change of a share {worst:.3} points");
                for (a, b) in values.iter().zip(&tv) {
                    let d = (a.impulse_share - b.impulse_share).abs();
                    assert!(
                        d < 2.0,
                        "{rule:?} {deg}°: {} {:.2} % vs {:.2} %",
                        a.name,
                        a.impulse_share,
                        b.impulse_share
                    );
                }
            }
        }
    }

    /// Real walks: the footscan step of pressuRe is a right foot; the F-Scan insole of the
    /// left foot, whose midfoot contact lies towards column 0 (its image seen from the other
    /// face than MUN104's, so named right), has its medial side towards larger columns.
    #[test]
    fn real_walks_have_their_medial_side() {
        let root = env!("CARGO_MANIFEST_DIR");
        let read = |f: &str| crate::read_recording(format!("{root}/{f}")).unwrap();
        let rec = read("../../benches/data/footscan-pressuRe-barefoot.txt");
        let (m, _) = recording_regions(&rec, 0.0, 0..rec.n_frames(), RegionRule::Fine).unwrap();
        let axis = m.axis.unwrap();
        assert_eq!(axis.side, Side::Right);
        assert_eq!(axis.heel_toe_cue, HeelToeCue::CopPath);
        let rec = read("tests/data/FrasP01L.asf");
        let (m, v) = recording_regions(&rec, 0.0, 0..rec.n_frames(), RegionRule::Fine).unwrap();
        let axis = m.axis.unwrap();
        assert!(axis.medial[0] > 0.9, "{axis:?}");
        // Toes towards row 0, the heel at the other end.
        assert!(axis.direction[1] < -0.9, "{axis:?}");
        // The heel carries more of the impulse than the toes in this walk.
        let share = |n: &str| v.iter().find(|r| r.name == n).unwrap().impulse_share;
        assert!(
            share("heel_medial") + share("heel_lateral") > share("hallux") + share("lesser_toes")
        );
    }

    #[test]
    fn empty_and_tiny_footprints_are_typed_errors() {
        let e = foot_axis(&[0.0; 20], 4, 5, [5.0, 5.0], None).unwrap_err();
        assert!(matches!(e, IoError::NoObject(_)), "{e}");
        let mut img = vec![0.0; 20];
        img[3] = 1.0;
        img[4] = 2.0;
        let e = foot_axis(&img, 4, 5, [5.0, 5.0], None).unwrap_err();
        assert!(e.to_string().contains("too small"), "{e}");
        assert!(foot_axis(&img, 4, 4, [5.0, 5.0], None).is_err());
        assert!(foot_axis(&img, 4, 5, [0.0, 5.0], None).is_err());
        // NaN sensels (no sensor) are not footprint.
        let e =
            automatic_masks(&[f64::NAN; 20], 4, 5, [1.0, 1.0], None, RegionRule::Fine).unwrap_err();
        assert!(matches!(e, IoError::NoObject(_)));
    }

    #[test]
    fn region_curves_are_each_region_s_force_and_peak_over_each_stance() {
        // 14 frames of 1 × 3 sensels, 2 mm pitch, 100 Hz, kPa: sensels 0 and 1 are region
        // "a", sensel 2 region "b". Frames 1..=12 in contact (one stance of 12 frames).
        let n = 14;
        let mut data = vec![0.0f32; 3 * n];
        for t in 1..=12 {
            data[3 * t] = 100.0 * t as f32;
            data[3 * t + 1] = 50.0;
            data[3 * t + 2] = if t < 7 { 300.0 } else { 0.0 };
        }
        let rec = Recording::new(n, 1, 3, data, vec![true; 3])
            .unwrap()
            .with_pitch_mm([2.0, 2.0])
            .unwrap()
            .with_frame_rate(100.0)
            .unwrap()
            .with_units("kPa");
        let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
        assert_eq!(m.stances.len(), 1);
        assert_eq!(
            (m.stances[0].stance.first, m.stances[0].stance.last),
            (1, 12)
        );
        let masks = RegionMasks {
            rows: 1,
            cols: 3,
            labels: vec![1, 1, 2],
            names: vec!["a".into(), "b".into()],
            rule: None,
            axis: None,
            sides: Vec::new(),
            foot_axes: Vec::new(),
        };
        let mut series = RegionSeries::new(&rec, 0.0, &masks).unwrap();
        for t in 0..n {
            series.add_frame(&rec.frame_slice(t).unwrap()).unwrap();
        }
        let v = series.finish(&m).unwrap();
        let (a, b) = (&v[0].curves[0], &v[1].curves[0]);
        assert_eq!((a.force.len(), b.peak_pressure.len()), (101, 101));
        // Point p lies at frame 1 + 11 p / 100; at 50 %: frame 6.5, between frames 6 and 7.
        // Region a: (100 t + 50) kPa × 4 mm² = (0.4 t + 0.2) N → 2.8 N; its peak 100 t → 650.
        assert!((a.force[50] - 2.8).abs() < 1e-9, "{}", a.force[50]);
        assert!((a.peak_pressure[50] - 650.0).abs() < 1e-9);
        // Region b: 1.2 N up to frame 6, 0 from frame 7: halfway, 0.6 N and 150 kPa.
        assert!((b.force[50] - 0.6).abs() < 1e-9, "{}", b.force[50]);
        assert!((b.peak_pressure[50] - 150.0).abs() < 1e-9);
        assert_eq!((b.force[0], b.force[100]), (1.2, 0.0));
        assert!((a.force[100] - 5.0).abs() < 1e-9);
        // The regions' forces add up to the stance's force curve.
        let total = &m.stances[0].curves.force;
        for (p, ((fa, fb), t)) in a.force.iter().zip(&b.force).zip(total).enumerate() {
            assert!((fa + fb - t).abs() < 1e-9, "{p}");
        }
        // Frames that are not the measures' are refused.
        let mut short = RegionSeries::new(&rec, 0.0, &masks).unwrap();
        short.add_frame(&rec.frame_slice(0).unwrap()).unwrap();
        assert!(short.finish(&m).is_err());
    }

    #[test]
    fn a_users_region_is_split_into_its_part_on_each_insole() {
        use crate::recording::FootColumns;
        // Region a spans both insoles (columns 0..2 and 3..5), region b the right one only.
        let masks = RegionMasks {
            rows: 2,
            cols: 5,
            labels: vec![1, 1, 0, 1, 1, 0, 0, 0, 2, 2],
            names: vec!["a".into(), "b".into()],
            rule: None,
            axis: None,
            sides: Vec::new(),
            foot_axes: Vec::new(),
        };
        let feet = [
            FootColumns {
                side: Side::Right,
                columns: 3..5,
            },
            FootColumns {
                side: Side::Left,
                columns: 0..2,
            },
        ];
        let split = masks.clone().per_foot(&feet).unwrap();
        assert_eq!(split.names, ["a", "a", "b"]);
        assert_eq!(split.sides, [Side::Left, Side::Right, Side::Right]);
        assert_eq!(split.labels, [1, 1, 0, 2, 2, 0, 0, 0, 3, 3]);
        assert_eq!(split.side_of(3), Some(Side::Right));
        // Without feet, or divided already, the masks are unchanged.
        assert_eq!(masks.clone().per_foot(&[]).unwrap(), masks);
        assert_eq!(split.clone().per_foot(&feet).unwrap(), split);
    }
}
