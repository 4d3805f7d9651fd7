//! Synthetic recordings with a known motion: ground truth for node tracks.
//!
//! A foot-like pressure field (a sum of anisotropic Gaussians: heel, lateral midfoot band,
//! metatarsal heads, hallux, on a broad sole) is warped smoothly in time. The warp of frame `t`
//! maps a point of frame 0 to where the same material point lies in frame `t`:
//!
//! `φ_t(p) = c + T(s) + R(θ(s)) · (W_s(p) − c)`, with `s = t / (frames − 1)`,
//!
//! - `W_s` spreads the forefoot sideways: `x ↦ c_x + (1 + spread · s · w(y)) (x − c_x)`, where
//!   `w(y)` rises smoothly from 0 at the heel to 1 at the forefoot (a non-affine warp);
//! - `R(θ)` turns by `θ(s) = rotation · s` about the foot's centre `c`;
//! - `T(s)` translates by `s · translation` (default heel→toe: towards row 0).
//!
//! Frame `t` holds `f(φ_t⁻¹(x))`: pressure is carried with the material, so the contour at the
//! noise threshold of frame `t` is the image under `φ_t` of frame 0's contour, and
//! [`SyntheticWalk::true_position`] says where every node of frame 0 should be in frame `t`.

use crate::error::{IoError, Result};
use crate::recording::Recording;

/// Parameters of a synthetic walk. Lengths in sensels, angles in degrees, pressures in kPa.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticWalk {
    /// Number of frames (≥ 2).
    pub frames: usize,
    /// Rows of the grid (y extent, ≥ 8).
    pub rows: usize,
    /// Columns of the grid (x extent, ≥ 8).
    pub cols: usize,
    /// Translation `[dx, dy]` reached at the last frame (sensels).
    pub translation: [f64; 2],
    /// Rotation reached at the last frame, counter-clockwise in the image (degrees).
    pub rotation_deg: f64,
    /// Relative widening of the forefoot reached at the last frame (0.1 = 10 %).
    pub spread: f64,
    /// Noise threshold written into the recording (kPa): the loaded region's edge.
    pub noise_kpa: f64,
    /// Sensor pitch written into the recording (mm per sensel, square sensels).
    pub pitch_mm: f64,
    /// Frame rate written into the recording (Hz).
    pub frame_rate_hz: f64,
}

impl Default for SyntheticWalk {
    /// 120 frames of 84 rows × 40 columns: the foot (about 16 × 48 sensels) moves 10 sensels
    /// towards the toes, turns by 12° and its forefoot widens by 15 %.
    fn default() -> Self {
        Self {
            frames: 120,
            rows: 84,
            cols: 40,
            translation: [0.0, -10.0],
            rotation_deg: 12.0,
            spread: 0.15,
            noise_kpa: 10.0,
            pitch_mm: 5.0,
            frame_rate_hz: 100.0,
        }
    }
}

/// One anisotropic Gaussian of the reference field: centre, σ along x and y, peak (kPa).
struct Blob {
    centre: [f64; 2],
    sigma: [f64; 2],
    peak: f64,
}

impl SyntheticWalk {
    /// The foot's centre `c` in frame 0 (rotation and spreading are about it).
    pub fn centre(&self) -> [f64; 2] {
        [self.cols as f64 / 2.0, self.rows as f64 / 2.0 + 3.0]
    }

    /// The reference (frame-0) field, in sensel coordinates relative to [`centre`](Self::centre):
    /// heel at +y (large rows), toes at −y. The hallux and the heel are deliberately unlike, so
    /// that the outline has no symmetry a matcher could confuse.
    fn blobs() -> [Blob; 9] {
        let b = |cx, cy, sx, sy, peak| Blob {
            centre: [cx, cy],
            sigma: [sx, sy],
            peak,
        };
        [
            b(0.0, 2.0, 6.5, 18.0, 45.0),    // sole
            b(0.5, 17.0, 4.8, 5.5, 320.0),   // heel
            b(4.0, 3.0, 2.6, 7.0, 90.0),     // lateral midfoot band
            b(-4.5, -12.0, 2.8, 2.8, 260.0), // first metatarsal head
            b(-0.5, -13.0, 2.6, 2.6, 230.0), // second
            b(3.5, -11.5, 2.6, 2.6, 190.0),  // third/fourth
            b(6.5, -9.0, 2.4, 2.6, 150.0),   // fifth
            b(-5.0, -22.0, 2.4, 2.8, 210.0), // hallux
            b(2.5, -20.0, 3.5, 1.8, 90.0),   // lesser toes
        ]
    }

    /// The reference field at `p` (frame-0 sensel coordinates).
    fn field(&self, p: [f64; 2]) -> f64 {
        let c = self.centre();
        let (x, y) = (p[0] - c[0], p[1] - c[1]);
        Self::blobs()
            .iter()
            .map(|b| {
                let u = (x - b.centre[0]) / b.sigma[0];
                let v = (y - b.centre[1]) / b.sigma[1];
                b.peak * (-0.5 * (u * u + v * v)).exp()
            })
            .sum()
    }

    /// Progress `s ∈ [0, 1]` of frame `t`.
    fn progress(&self, t: usize) -> f64 {
        t as f64 / (self.frames.max(2) - 1) as f64
    }

    /// Forefoot weight `w(y)`: 0 at the heel, 1 at the toes, smooth in between (relative y).
    fn forefoot_weight(y_rel: f64) -> f64 {
        1.0 / (1.0 + (y_rel / 6.0).exp())
    }

    /// Where the material point at `p` in frame 0 lies in frame `t` (`φ_t(p)`, sensels).
    pub fn true_position(&self, t: usize, p: [f64; 2]) -> [f64; 2] {
        let s = self.progress(t);
        let c = self.centre();
        let widen = 1.0 + self.spread * s * Self::forefoot_weight(p[1] - c[1]);
        let (wx, wy) = (widen * (p[0] - c[0]), p[1] - c[1]);
        let (sin, cos) = (self.rotation_deg * s).to_radians().sin_cos();
        [
            c[0] + s * self.translation[0] + cos * wx - sin * wy,
            c[1] + s * self.translation[1] + sin * wx + cos * wy,
        ]
    }

    /// Where the material point at `q` in frame `t` lay in frame 0 (`φ_t⁻¹(q)`).
    pub fn reference_position(&self, t: usize, q: [f64; 2]) -> [f64; 2] {
        let s = self.progress(t);
        let c = self.centre();
        let (dx, dy) = (
            q[0] - c[0] - s * self.translation[0],
            q[1] - c[1] - s * self.translation[1],
        );
        let (sin, cos) = (self.rotation_deg * s).to_radians().sin_cos();
        let (wx, wy) = (cos * dx + sin * dy, -sin * dx + cos * dy);
        let widen = 1.0 + self.spread * s * Self::forefoot_weight(wy);
        [c[0] + wx / widen, c[1] + wy]
    }

    /// Checks the parameters: at least 2 frames, a grid of at least 8 × 8, a finite
    /// translation, rotation, spread and noise threshold, a spread above −1 and a noise
    /// threshold ≥ 0. The pitch and frame rate are checked (finite, > 0) by
    /// [`recording`](Self::recording).
    pub fn validate(&self) -> Result<()> {
        let finite = self.translation.iter().all(|v| v.is_finite())
            && self.rotation_deg.is_finite()
            && self.spread.is_finite()
            && self.noise_kpa.is_finite();
        if self.frames < 2 || self.rows < 8 || self.cols < 8 {
            return Err(IoError::invalid(format!(
                "a synthetic walk needs at least 2 frames of 8 x 8, got {} x {}x{}",
                self.frames, self.rows, self.cols
            )));
        }
        if !finite || self.spread <= -1.0 || self.noise_kpa < 0.0 {
            return Err(IoError::invalid(format!(
                "synthetic walk parameters must be finite, spread > -1 and noise >= 0: {self:?}"
            )));
        }
        Ok(())
    }

    /// The recording: frame `t` samples the reference field at `φ_t⁻¹` of every sensel centre.
    /// Carries the pitch, frame rate, units (kPa) and noise threshold.
    pub fn recording(&self) -> Result<Recording> {
        self.validate()?;
        let (rows, cols) = (self.rows, self.cols);
        let mut data = Vec::with_capacity(self.frames * rows * cols);
        for t in 0..self.frames {
            for r in 0..rows {
                for c in 0..cols {
                    let p = self.reference_position(t, [c as f64, r as f64]);
                    data.push(self.field(p) as f32);
                }
            }
        }
        let mut rec = Recording::new(self.frames, rows, cols, data, vec![true; rows * cols])?
            .with_pitch_mm([self.pitch_mm; 2])?
            .with_frame_rate(self.frame_rate_hz)?
            .with_units("kPa");
        rec.noise_threshold = Some(self.noise_kpa);
        Ok(rec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inverse_undoes_the_warp() {
        let w = SyntheticWalk::default();
        for t in [0, 1, 37, 119] {
            for p in [[20.0, 40.0], [12.5, 17.0], [27.0, 60.0], [3.0, 5.0]] {
                let q = w.true_position(t, p);
                let back = w.reference_position(t, q);
                assert!(
                    (back[0] - p[0]).abs() < 1e-9 && (back[1] - p[1]).abs() < 1e-9,
                    "t={t} p={p:?} back={back:?}"
                );
            }
        }
        assert_eq!(w.true_position(0, [11.0, 7.0]), [11.0, 7.0]);
    }

    #[test]
    fn the_warp_moves_the_field_with_the_material() {
        let w = SyntheticWalk {
            frames: 5,
            ..Default::default()
        };
        let rec = w.recording().unwrap();
        // The heel peak of frame 0 is found again at its true position in the last frame.
        let c = w.centre();
        let heel0 = [c[0] + 0.5, c[1] + 17.0];
        let heel4 = w.true_position(4, heel0);
        let (r, col) = (heel4[1].round() as usize, heel4[0].round() as usize);
        let f4 = rec.frame(4).unwrap();
        let v = f4.get(r, col);
        let around = [(r - 3, col), (r + 3, col), (r, col - 3), (r, col + 3)];
        assert!(around.iter().all(|&(rr, cc)| f4.get(rr, cc) < v));
        // The foot stays inside the grid (nothing loaded on the border).
        for t in 0..5 {
            let f = rec.frame(t).unwrap();
            for r in 0..w.rows {
                for cc in [0, w.cols - 1] {
                    assert!(f.get(r, cc) < w.noise_kpa);
                }
            }
            for cc in 0..w.cols {
                for r in [0, w.rows - 1] {
                    assert!(f.get(r, cc) < w.noise_kpa);
                }
            }
        }
        assert!(w.recording().is_ok());
        assert!(SyntheticWalk {
            frames: 1,
            ..Default::default()
        }
        .recording()
        .is_err());
    }
}
