//! Stances: the foot contacts of a recording, found in its force series, and series resampled
//! to 0–100 % of a stance (docs/measures.md).
//!
//! **The rule** ([`find_stances`]). A frame is *in contact* when its force exceeds
//! `min F + 10 % × (max F − min F)` of the frames measured (the automatic threshold of pressuRe's
//! `threshold_event`, the same as the contact time of [`crate::measures`]). A stance is a run of
//! frames in contact, where
//!
//! * a gap shorter than [`MIN_GAP_S`] (frames not in contact between two runs) does not end a
//!   stance: a noisy sensel or a dip at the threshold during loading or unloading does not split
//!   one contact in two (a hysteresis in time);
//! * a run shorter than [`MIN_STANCE_S`] is no stance (a spike of noise), as the minimum contact
//!   time of dryft's `split_steps` (R. Alcantara) drops what cannot be a step.
//!
//! Without a frame rate both durations are counted in frames at [`ASSUMED_RATE_HZ`] (3 and 5
//! frames). When every frame has the same force above 0 (a single frame, a static trial), the
//! frames are one stance. A stance that begins on the first frame measured or ends on the last
//! may have begun before or ended after it: it is marked not [`complete`](Stance::complete).
//!
//! **Resampling** ([`resample`]): a stance of `n` frames, frame `first` at 0 % and frame `last`
//! at 100 %, is read at [`CURVE_POINTS`] evenly spaced points, point `k` (k %) at frame position
//! `first + k (n − 1) / 100`, linearly between the two frames around it (as `numpy.interp`).

use crate::error::{IoError, Result};
use crate::measures::CONTACT_FORCE_FRACTION;

/// Gaps shorter than this (s) between frames in contact do not end a stance.
pub const MIN_GAP_S: f64 = 0.05;

/// Runs of frames in contact shorter than this (s) are no stance.
pub const MIN_STANCE_S: f64 = 0.1;

/// The frame rate the durations of the rule are counted at when a recording states none (Hz).
pub const ASSUMED_RATE_HZ: f64 = 50.0;

/// Points of a stance-normalised curve: 0, 1, …, 100 % of contact.
pub const CURVE_POINTS: usize = 101;

/// The stance rule in frames (see the [module](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StanceRule {
    /// The fraction of the force range above its minimum a frame must exceed to be in contact.
    pub fraction: f64,
    /// Gaps of fewer frames than this do not end a stance.
    pub min_gap: usize,
    /// Runs of fewer frames than this are no stance.
    pub min_frames: usize,
}

impl StanceRule {
    /// The rule for frames `dt_s` seconds apart ([`ASSUMED_RATE_HZ`] when unknown): gaps of
    /// fewer than `⌈MIN_GAP_S / dt⌉` frames joined, runs of fewer than `⌈MIN_STANCE_S / dt⌉`
    /// frames dropped.
    ///
    /// ```
    /// use pedo_io::stances::StanceRule;
    /// let r = StanceRule::for_interval(Some(0.01)); // 100 Hz
    /// assert_eq!((r.min_gap, r.min_frames), (5, 10));
    /// let r = StanceRule::for_interval(None); // counted at 50 Hz
    /// assert_eq!((r.min_gap, r.min_frames), (3, 5));
    /// ```
    pub fn for_interval(dt_s: Option<f64>) -> Self {
        let dt = dt_s
            .filter(|d| d.is_finite() && *d > 0.0)
            .unwrap_or(1.0 / ASSUMED_RATE_HZ);
        // The tolerance keeps 0.05 / 0.01 at 5 frames, not 6.
        let frames = |s: f64| ((s / dt) * (1.0 - 1e-9)).ceil().clamp(1.0, 1e9) as usize;
        Self {
            fraction: CONTACT_FORCE_FRACTION,
            min_gap: frames(MIN_GAP_S),
            min_frames: frames(MIN_STANCE_S),
        }
    }
}

/// One stance: frames `first..=last` (the recording's frame numbers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stance {
    /// The first frame over the threshold (0 % of contact).
    pub first: usize,
    /// The last frame over the threshold (100 % of contact).
    pub last: usize,
    /// Whether the frame before and the frame after the stance were measured (and not in
    /// contact): a stance on the first or last frame measured may be cut by the recording.
    pub complete: bool,
}

impl Stance {
    /// Its number of frames, `last − first + 1`.
    pub fn frames(&self) -> usize {
        self.last - self.first + 1
    }
}

/// The stances of a force series (see the [module](self)): `forces[k]` is the force of frame
/// `first_frame + k`. Returns the contact threshold and the stances in frame order.
///
/// # Errors
///
/// [`IoError::InvalidInput`] when `forces` is empty or holds a value that is not finite.
///
/// ```
/// use pedo_io::stances::{find_stances, StanceRule};
/// let rule = StanceRule { fraction: 0.1, min_gap: 2, min_frames: 2 };
/// // Two steps; the dip of one frame at frame 4 does not split the first.
/// let f = [0.0, 50.0, 100.0, 80.0, 5.0, 90.0, 40.0, 0.0, 0.0, 60.0, 70.0, 0.0];
/// let (threshold, s) = find_stances(&f, 10, &rule)?;
/// assert_eq!(threshold, 10.0);
/// assert_eq!(s.iter().map(|s| (s.first, s.last)).collect::<Vec<_>>(), [(11, 16), (19, 20)]);
/// # Ok::<(), pedo_io::IoError>(())
/// ```
pub fn find_stances(
    forces: &[f64],
    first_frame: usize,
    rule: &StanceRule,
) -> Result<(f64, Vec<Stance>)> {
    if forces.is_empty() {
        return Err(IoError::invalid("no frame to find stances in"));
    }
    if let Some(k) = forces.iter().position(|f| !f.is_finite()) {
        return Err(IoError::invalid(format!(
            "the force of frame {} is not finite",
            first_frame + k
        )));
    }
    let (lo, hi) = forces
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
            (lo.min(f), hi.max(f))
        });
    let threshold = lo + rule.fraction * (hi - lo);
    let n = forces.len();
    if hi == lo {
        let all = Stance {
            first: first_frame,
            last: first_frame + n - 1,
            complete: false,
        };
        return Ok((threshold, if hi > 0.0 { vec![all] } else { Vec::new() }));
    }
    // Runs of frames over the threshold, as index ranges (inclusive).
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut k = 0;
    while k < n {
        if forces[k] > threshold {
            let a = k;
            while k + 1 < n && forces[k + 1] > threshold {
                k += 1;
            }
            match runs.last_mut() {
                // A short gap: the same stance.
                Some(last) if a - last.1 - 1 < rule.min_gap => last.1 = k,
                _ => runs.push((a, k)),
            }
        }
        k += 1;
    }
    let stances = runs
        .into_iter()
        .filter(|(a, b)| b - a + 1 >= rule.min_frames)
        .map(|(a, b)| Stance {
            first: first_frame + a,
            last: first_frame + b,
            complete: a > 0 && b + 1 < n,
        })
        .collect();
    Ok((threshold, stances))
}

/// The series `values` of a stance's frames (first at 0 %, last at 100 %) at [`CURVE_POINTS`]
/// points of its contact (see the [module](self)); `None` values (e.g. a centre of pressure of a
/// frame without load) are skipped, the points read between the frames that have one (held at
/// the nearest one beyond them, as `numpy.interp`); all `None` without any.
///
/// ```
/// use pedo_io::stances::resample;
/// let c = resample(&[Some(0.0), Some(10.0), Some(30.0)]);
/// assert_eq!(c.len(), 101);
/// assert_eq!((c[0], c[25], c[50], c[75], c[100]), (Some(0.0), Some(5.0), Some(10.0), Some(20.0), Some(30.0)));
/// ```
pub fn resample(values: &[Option<f64>]) -> Vec<Option<f64>> {
    let known: Vec<(f64, f64)> = values
        .iter()
        .enumerate()
        .filter_map(|(k, v)| v.map(|v| (k as f64, v)))
        .collect();
    let Some(&(x0, y0)) = known.first() else {
        return vec![None; CURVE_POINTS];
    };
    let (xn, yn) = known[known.len() - 1];
    let span = values.len().saturating_sub(1) as f64;
    let mut j = 0;
    (0..CURVE_POINTS)
        .map(|p| {
            let x = span * p as f64 / (CURVE_POINTS - 1) as f64;
            if x <= x0 {
                return Some(y0);
            }
            if x >= xn {
                return Some(yn);
            }
            while known[j + 1].0 <= x {
                j += 1;
            }
            let ((xa, ya), (xb, yb)) = (known[j], known[j + 1]);
            Some(ya + (yb - ya) * (x - xa) / (xb - xa))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spans(s: &[Stance]) -> Vec<(usize, usize, bool)> {
        s.iter().map(|s| (s.first, s.last, s.complete)).collect()
    }

    /// A deterministic noise in [−1, 1) (a linear congruential generator).
    fn noise(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// Steps of `len` frames (a half sine of 800 N) every `period` frames from `start`, with
    /// noise of ±`amp` N on every frame, clamped at 0.
    fn walk(n: usize, start: usize, len: usize, period: usize, amp: f64) -> Vec<f64> {
        let mut seed = 7;
        (0..n)
            .map(|t| {
                let base = if t >= start && (t - start) % period < len {
                    let k = (t - start) % period;
                    800.0 * (std::f64::consts::PI * (k as f64 + 0.5) / len as f64).sin()
                } else {
                    0.0
                };
                (base + amp * noise(&mut seed)).max(0.0)
            })
            .collect()
    }

    #[test]
    fn noisy_steps_are_found_whole_and_the_noise_between_them_is_no_stance() {
        // 100 Hz: 0.6 s steps every 1.1 s, ±15 N of noise (more than a noisy sensel of an
        // insole adds) both in contact and in the swing.
        let rule = StanceRule::for_interval(Some(0.01));
        let f = walk(500, 30, 60, 110, 15.0);
        let (threshold, s) = find_stances(&f, 0, &rule).unwrap();
        assert!((70.0..100.0).contains(&threshold), "{threshold}");
        let got = spans(&s);
        assert_eq!(got.len(), 5, "{got:?}");
        for (k, (a, b, complete)) in got.into_iter().enumerate() {
            // The last step is cut by the end of the recording.
            let (start, end) = (30 + 110 * k, (30 + 110 * k + 59).min(499));
            // The half sine exceeds 10 % of its height after about 3 % of the step.
            assert!(a >= start && a <= start + 4, "{k}: {a} vs {start}");
            assert!(b <= end && b + 4 >= end, "{k}: {b} vs {end}");
            assert_eq!(complete, k < 4, "{k}");
        }
    }

    #[test]
    fn a_dip_below_the_threshold_splits_a_stance_only_when_it_lasts() {
        let rule = StanceRule {
            fraction: 0.1,
            min_gap: 3,
            min_frames: 1,
        };
        let mut f = vec![
            0.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 0.0,
        ];
        // Two frames under 10 N: shorter than 3 frames, one stance.
        f[4] = 5.0;
        f[5] = 5.0;
        let (_, s) = find_stances(&f, 0, &rule).unwrap();
        assert_eq!(spans(&s), [(1, 8, true)]);
        // Three: two stances, touching through the gap.
        f[6] = 10.0; // at the threshold is not over it
        let (threshold, s) = find_stances(&f, 0, &rule).unwrap();
        assert_eq!(threshold, 10.0);
        assert_eq!(spans(&s), [(1, 3, true), (7, 8, true)]);
        // Stances that touch: no frame between them under the threshold is one stance.
        let f = [0.0, 100.0, 50.0, 100.0, 0.0];
        let (_, s) = find_stances(&f, 0, &rule).unwrap();
        assert_eq!(spans(&s), [(1, 3, true)]);
    }

    #[test]
    fn short_runs_are_no_stance() {
        let rule = StanceRule {
            fraction: 0.1,
            min_gap: 1,
            min_frames: 3,
        };
        let f = [
            0.0, 500.0, 0.0, 0.0, 400.0, 400.0, 400.0, 0.0, 300.0, 300.0, 0.0,
        ];
        let (_, s) = find_stances(&f, 100, &rule).unwrap();
        assert_eq!(spans(&s), [(104, 106, true)]);
    }

    #[test]
    fn a_recording_that_starts_or_ends_in_contact_has_incomplete_stances() {
        let rule = StanceRule::for_interval(Some(0.032));
        assert_eq!((rule.min_gap, rule.min_frames), (2, 4));
        // The bundled walk's first frames: in contact from frame 0.
        let f = [
            846.0, 859.0, 871.0, 900.0, 592.0, 30.0, 0.0, 2.0, 0.0, 0.0, 98.0, 334.0, 700.0, 500.0,
            100.0, 120.0,
        ];
        let (_, s) = find_stances(&f, 0, &rule).unwrap();
        assert_eq!(spans(&s), [(0, 4, false), (10, 15, false)]);
    }

    #[test]
    fn constant_force_is_one_stance_and_no_force_none() {
        let rule = StanceRule::for_interval(None);
        let (_, s) = find_stances(&[7.0], 3, &rule).unwrap();
        assert_eq!(spans(&s), [(3, 3, false)]);
        let (_, s) = find_stances(&[0.0, 0.0], 0, &rule).unwrap();
        assert!(s.is_empty());
        assert!(find_stances(&[], 0, &rule).is_err());
        let e = find_stances(&[1.0, f64::NAN], 5, &rule).unwrap_err();
        assert!(e.to_string().contains("frame 6"), "{e}");
    }

    #[test]
    fn resampling_is_linear_between_frames_and_skips_frames_without_a_value() {
        // 5 frames: position of point k is 4k/100; hand computed at 0, 10, 30, 62.5 (k) %.
        let v = [Some(0.0), Some(10.0), Some(-10.0), Some(20.0), Some(40.0)];
        let c = resample(&v);
        let at = |k: usize| c[k].unwrap();
        assert_eq!(at(0), 0.0);
        assert!((at(10) - 4.0).abs() < 1e-12); // 0.4 of the way from 0 to 10
        assert!((at(30) - 6.0).abs() < 1e-12); // position 1.2: 10 − 0.2 × 20
        assert!((at(80) - 24.0).abs() < 1e-12); // position 3.2: 20 + 0.2 × 20
        assert_eq!(at(100), 40.0);
        // One frame: its value all along.
        assert_eq!(resample(&[Some(3.0)]), vec![Some(3.0); CURVE_POINTS]);
        // A frame without a value is skipped; beyond the known frames the nearest is held.
        let c = resample(&[None, Some(2.0), None, Some(6.0), None]);
        assert_eq!(c[0], Some(2.0));
        assert_eq!(c[25], Some(2.0));
        assert!((c[50].unwrap() - 4.0).abs() < 1e-12);
        assert_eq!(c[100], Some(6.0));
        assert_eq!(resample(&[None, None]), vec![None; CURVE_POINTS]);
    }
}
