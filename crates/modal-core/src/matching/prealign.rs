//! Pre-alignment of two objects (docs/method.md §5.3 and §7): normalisation,
//! principal-axis rotation candidates, symmetric affine ICP scored by chamfer distance, and
//! least-squares affine fits from correspondences.

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use std::borrow::Cow;

use rayon::prelude::*;

use super::outline_fit;
use crate::error::ModalError;
use crate::simd::{dispatch, Kernel};

/// How the two objects are brought into a common frame before their modes are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Prealign {
    /// Centroid and RMS scale only (the paper's setting; enough for consecutive frames).
    Normalize,
    /// Centroid, scale, rotation candidates scored by chamfer after symmetric affine ICP (§10).
    #[default]
    Robust,
    /// The callers' coordinates are the prior (consecutive frames of one recording share the
    /// sensor's coordinates): A starts where it lies in B's coordinates, with no centroid, scale
    /// or rotation normalisation between the two, and only the modal affine re-fits move it. A
    /// part of a region stays on its own portion of the whole instead of being spread over it.
    Sensor,
}

impl Prealign {
    /// Whether A is re-normalised into B's frame after an affine map (see [`into_b_frame`]):
    /// never with [`Prealign::Sensor`], whose point is to keep A's placement and size.
    pub(crate) fn renormalizes(self, ordered: bool) -> bool {
        ordered && self != Prealign::Sensor
    }
}

/// A `dim`-dimensional affine map `x ↦ M x + t` (only the leading `dim × dim` block is used).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Affine {
    /// Dimension of the points (2 or 3).
    pub dim: usize,
    /// The linear part `M`, row-major.
    pub m: [[f64; 3]; 3],
    /// The translation `t`.
    pub t: [f64; 3],
}

impl Affine {
    /// The identity map in `dim` dimensions.
    pub fn identity(dim: usize) -> Self {
        let mut m = [[0.0; 3]; 3];
        for (a, row) in m.iter_mut().enumerate() {
            row[a] = 1.0;
        }
        Self {
            dim,
            m,
            t: [0.0; 3],
        }
    }

    /// The linear map `x ↦ M x` (no translation).
    pub fn linear(dim: usize, m: [[f64; 3]; 3]) -> Self {
        Self {
            dim,
            m,
            t: [0.0; 3],
        }
    }

    /// Applies the map to row-major points.
    pub fn apply(&self, pts: &[f64]) -> Vec<f64> {
        let d = self.dim;
        let mut out = vec![0.0; pts.len()];
        for (p, o) in pts.chunks_exact(d).zip(out.chunks_exact_mut(d)) {
            for a in 0..d {
                o[a] = self.t[a] + (0..d).map(|b| self.m[a][b] * p[b]).sum::<f64>();
            }
        }
        out
    }

    /// `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Affine) -> Affine {
        let d = self.dim;
        let mut r = Affine::identity(d);
        for a in 0..d {
            for b in 0..d {
                r.m[a][b] = (0..d).map(|c| self.m[a][c] * other.m[c][b]).sum();
            }
            r.t[a] = self.t[a] + (0..d).map(|c| self.m[a][c] * other.t[c]).sum::<f64>();
        }
        r
    }

    /// Whether every entry of `M − I` and of `t` is below `tol` in magnitude: an ICP step that
    /// no longer moves anything.
    pub(crate) fn is_within_of_identity(&self, tol: f64) -> bool {
        (0..self.dim).all(|r| {
            self.t[r].abs() < tol
                && (0..self.dim)
                    .all(|c| (self.m[r][c] - if r == c { 1.0 } else { 0.0 }).abs() < tol)
        })
    }

    /// Determinant of the linear part's leading `dim × dim` block.
    pub fn det(&self) -> f64 {
        let m = &self.m;
        if self.dim == 2 {
            m[0][0] * m[1][1] - m[0][1] * m[1][0]
        } else {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        }
    }
}

/// Centres points on their centroid and scales them to RMS radius 1 (docs/method.md §5.3).
/// Returns the normalised points, the centroid and the scale factor applied.
pub fn normalize(pts: &[f64], dim: usize) -> Result<(Vec<f64>, [f64; 3], f64), ModalError> {
    let n = pts.len() / dim;
    if n == 0 {
        return Err(ModalError::TooFewNodes { nodes: 0, min: 1 });
    }
    let mut c = [0.0; 3];
    for p in pts.chunks_exact(dim) {
        for a in 0..dim {
            c[a] += p[a] / n as f64;
        }
    }
    let extent = pts.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    // The spread is summed in units of a power of two near the extent (an exact rescaling):
    // squares of coordinates near 1e300, finite as they are, would overflow.
    let unit = 2f64.powi(extent.log2().floor().clamp(-1000.0, 1000.0) as i32);
    let ms: f64 = pts
        .chunks_exact(dim)
        .map(|p| {
            (0..dim)
                .map(|a| (p[a] / unit - c[a] / unit).powi(2))
                .sum::<f64>()
        })
        .sum::<f64>()
        / n as f64;
    let rms = ms.sqrt() * unit;
    if !(rms.is_finite() && rms > 1e-12 * extent) {
        return Err(ModalError::ZeroExtent);
    }
    let s = 1.0 / rms;
    let out = pts
        .chunks_exact(dim)
        .flat_map(|p| (0..dim).map(move |a| (p[a] - c[a]) * s))
        .collect();
    Ok((out, c, s))
}

/// Signed area of a closed 2-D polygon (positive when counter-clockwise).
pub(crate) fn signed_area(pts: &[f64]) -> f64 {
    let n = pts.len() / 2;
    (0..n)
        .map(|i| {
            let j = (i + 1) % n;
            pts[2 * i] * pts[2 * j + 1] - pts[2 * j] * pts[2 * i + 1]
        })
        .sum::<f64>()
        * 0.5
}

/// Eigen-decomposition of a symmetric 3×3 matrix (nalgebra's symmetric eigensolver).
/// Returns eigenvalues and eigenvectors as columns (`vecs[row][k]` for eigenvalue `k`), unsorted;
/// each vector has its largest entry positive.
pub fn sym_eigen3(a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    crate::geometry::sym_eigen3(&a)
}

/// Principal axes of centred points: columns sorted by descending variance, determinant +1,
/// together with the variances.
pub fn principal_axes(pts: &[f64], dim: usize) -> ([[f64; 3]; 3], [f64; 3]) {
    let mut cov = [[0.0; 3]; 3];
    for p in pts.chunks_exact(dim) {
        for a in 0..dim {
            for b in 0..dim {
                cov[a][b] += p[a] * p[b];
            }
        }
    }
    let (vals, vecs) = if dim == 2 {
        // The padding axis sorts last.
        crate::geometry::sym_eigen2_padded(&cov, -1.0)
    } else {
        crate::geometry::sym_eigen3(&cov)
    };
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&x, &y| vals[y].total_cmp(&vals[x]));
    let mut out = [[0.0; 3]; 3];
    let mut var = [0.0; 3];
    for (col, &k) in idx.iter().enumerate() {
        for row in 0..3 {
            out[row][col] = vecs[row][k];
        }
        var[col] = vals[k];
    }
    let aff = Affine::linear(dim, out);
    if aff.det() < 0.0 {
        for row in out.iter_mut() {
            row[dim - 1] = -row[dim - 1];
        }
    }
    (out, var)
}

/// Index and squared distance of the nearest point of `to` for every point of `from` (the first
/// such point on ties).
pub(crate) fn nearest(from: &[f64], to: &[f64], dim: usize) -> Vec<(usize, f64)> {
    match dim {
        2 => nearest_soa::<2, false>(from, to).0,
        3 => nearest_soa::<3, false>(from, to).0,
        _ => from
            .chunks_exact(dim)
            .map(|p| {
                let mut best = (0, f64::INFINITY);
                for (j, q) in to.chunks_exact(dim).enumerate() {
                    let d: f64 = (0..dim).map(|a| (p[a] - q[a]).powi(2)).sum();
                    if d < best.1 {
                        best = (j, d);
                    }
                }
                best
            })
            .collect(),
    }
}

/// [`nearest`] both ways in one scan: `(nearest(from, to), nearest(to, from))`, same ties.
pub(crate) fn nearest_both(from: &[f64], to: &[f64], dim: usize) -> NearestBoth {
    match dim {
        2 => nearest_soa::<2, true>(from, to),
        3 => nearest_soa::<3, true>(from, to),
        _ => (nearest(from, to, dim), nearest(to, from, dim)),
    }
}

/// Nearest neighbours from every point of `from` into `to` and, with `COLS`, from every point of
/// `to` into `from`, in one structure-of-arrays scan (ICP and the re-fit loop call this thousands
/// of times per pair). Ties go to the first index, as in a plain scan. Planar and 3-D point sets
/// take an AVX-512 kernel when the CPU has one; planar ones, by far the most frequent, an AVX2
/// kernel otherwise.
fn nearest_soa<const D: usize, const COLS: bool>(from: &[f64], to: &[f64]) -> NearestBoth {
    dispatch(NearestSoa::<D, COLS> { from, to })
}

/// The arguments of [`nearest_soa`], run by [`dispatch`].
struct NearestSoa<'a, const D: usize, const COLS: bool> {
    from: &'a [f64],
    to: &'a [f64],
}

impl<const D: usize, const COLS: bool> Kernel for NearestSoa<'_, D, COLS> {
    type Output = NearestBoth;
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx512(self, simd: pulp::x86::V4) -> NearestBoth {
        let (n, m) = (self.from.len() / D, self.to.len() / D);
        if !(D == 2 || D == 3) || n == 0 || m == 0 {
            return nearest_soa_body::<D, COLS>(self.from, self.to);
        }
        nearest_avx512::<D, COLS>(simd, self.from, self.to)
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self, simd: pulp::x86::V3) -> NearestBoth {
        let (n, m) = (self.from.len() / D, self.to.len() / D);
        if D != 2 || n == 0 || m == 0 {
            return nearest_soa_body::<D, COLS>(self.from, self.to);
        }
        nearest_planar_avx2::<COLS>(simd, self.from, self.to)
    }
    #[inline(always)]
    fn baseline(self) -> NearestBoth {
        nearest_soa_body::<D, COLS>(self.from, self.to)
    }
}

/// Nearest neighbours one way and the other: `(index, squared distance)` per point of each set.
pub(crate) type NearestBoth = (Vec<(usize, f64)>, Vec<(usize, f64)>);

/// Rows of `from` that share a pass over the blocks of `to` in the planar kernels: a block's
/// column minima are then loaded and stored once per group, not once per row.
#[cfg(target_arch = "x86_64")]
const GROUP: usize = 4;

/// Points of `to` whose blocks a planar kernel keeps on the stack (on the heap beyond): room to
/// spare for the 40–80 of a contour in the pipeline, and no allocation.
#[cfg(target_arch = "x86_64")]
const STACK_POINTS: usize = 128;

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{__m256d, __m512d, __m512i, _CMP_EQ_OQ, _CMP_LT_OQ};

/// Four points of `to` for the AVX2 scan, with the nearest row so far of each, as f64: AVX2 has no
/// 64-bit integer `max` (see [`rows_avx2`]), and f64 holds an index exactly.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Block256 {
    x: __m256d,
    y: __m256d,
    v: __m256d,
    i: __m256d,
}

/// The planar scan on AVX2, written out with intrinsics, because the auto-vectoriser mixes 128-
/// and 256-bit halves in it. Separate multiply and add (no FMA) keep every distance
/// bit-identical to the plain scan's, so ties break alike. `from` and `to` are not empty.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn nearest_planar_avx2<const COLS: bool>(
    simd: pulp::x86::V3,
    from: &[f64],
    to: &[f64],
) -> NearestBoth {
    let a = simd.avx;
    let (n, m) = (from.len() / 2, to.len() / 2);
    let init = Block256 {
        x: a._mm256_setzero_pd(),
        y: a._mm256_setzero_pd(),
        v: a._mm256_set1_pd(f64::INFINITY),
        i: a._mm256_setzero_pd(),
    };
    let mut stack = [init; STACK_POINTS / 4];
    let mut heap = Vec::new();
    let blocks = m.div_ceil(4);
    let cols: &mut [Block256] = if blocks <= stack.len() {
        &mut stack[..blocks]
    } else {
        heap.resize(blocks, init);
        &mut heap
    };
    for (blk, q) in cols.iter_mut().zip(to.chunks(8)) {
        // NaN padding: its distances compare false, so padded lanes never hold a minimum.
        let (mut x, mut y) = ([f64::NAN; 4], [f64::NAN; 4]);
        for (l, p) in q.chunks_exact(2).enumerate() {
            (x[l], y[l]) = (p[0], p[1]);
        }
        (blk.x, blk.y) = (pulp::cast(x), pulp::cast(y));
    }
    let mut rows = vec![(0, 0.0); n];
    let mut groups = from
        .chunks_exact(2 * GROUP)
        .zip(rows.chunks_exact_mut(GROUP));
    for (g, (p, out)) in groups.by_ref().enumerate() {
        rows_avx2::<GROUP, COLS>(simd, p, GROUP * g, cols, out);
    }
    let i0 = n - n % GROUP;
    for (k, (p, out)) in from[2 * i0..]
        .chunks_exact(2)
        .zip(&mut rows[i0..])
        .enumerate()
    {
        rows_avx2::<1, COLS>(simd, p, i0 + k, cols, std::slice::from_mut(out));
    }
    let mut back = vec![(0, 0.0); if COLS { m } else { 0 }];
    for (blk, out) in cols.iter().zip(back.chunks_mut(4)) {
        let (v, i): ([f64; 4], [f64; 4]) = (pulp::cast(blk.v), pulp::cast(blk.i));
        for (o, (&v, &i)) in out.iter_mut().zip(v.iter().zip(&i)) {
            *o = (i as usize, v);
        }
    }
    (rows, back)
}

/// Rows `i0 .. i0 + R` (the points of `p`) against every block of four, their minima kept in
/// registers. A minimum is updated by `min` (`d < v ? d : v`, the strict update) and its index by
/// `max(index, better & current)`, exact because the current block (or row) index is never below
/// a kept one: two single-µop instructions where a blend costs two or three.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn rows_avx2<const R: usize, const COLS: bool>(
    simd: pulp::x86::V3,
    p: &[f64],
    i0: usize,
    cols: &mut [Block256],
    out: &mut [(usize, f64)],
) {
    let a = simd.avx;
    let zero = a._mm256_setzero_pd();
    let (mut px, mut py, mut row) = ([zero; R], [zero; R], [zero; R]);
    for r in 0..R {
        px[r] = a._mm256_set1_pd(p[2 * r]);
        py[r] = a._mm256_set1_pd(p[2 * r + 1]);
        row[r] = a._mm256_set1_pd((i0 + r) as f64);
    }
    let mut best_v = [a._mm256_set1_pd(f64::INFINITY); R];
    let mut best_b = [zero; R];
    let mut b = zero;
    for blk in cols.iter_mut() {
        let (mut cv, mut ci) = (blk.v, blk.i);
        for r in 0..R {
            let dx = a._mm256_sub_pd(blk.x, px[r]);
            let dy = a._mm256_sub_pd(blk.y, py[r]);
            let d = a._mm256_add_pd(a._mm256_mul_pd(dx, dx), a._mm256_mul_pd(dy, dy));
            let better = a._mm256_cmp_pd::<_CMP_LT_OQ>(d, best_v[r]);
            best_v[r] = a._mm256_min_pd(d, best_v[r]);
            best_b[r] = a._mm256_max_pd(best_b[r], a._mm256_and_pd(better, b));
            if COLS {
                // Rows come in increasing order: strict `<` keeps the first on ties.
                let better = a._mm256_cmp_pd::<_CMP_LT_OQ>(d, cv);
                cv = a._mm256_min_pd(d, cv);
                ci = a._mm256_max_pd(ci, a._mm256_and_pd(better, row[r]));
            }
        }
        if COLS {
            (blk.v, blk.i) = (cv, ci);
        }
        b = a._mm256_add_pd(b, a._mm256_set1_pd(1.0));
    }
    for r in 0..R {
        // Padded lanes keep (0, ∞), which never wins: no index bound needed.
        let (v, b): ([f64; 4], [f64; 4]) = (pulp::cast(best_v[r]), pulp::cast(best_b[r]));
        out[r] = reduce_lanes(&v, &b, usize::MAX);
    }
}

/// Eight points of `to` for the AVX-512 scan (their `D` coordinates), with the nearest row so
/// far of each.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Block512<const D: usize> {
    c: [__m512d; D],
    v: __m512d,
    i: __m512i,
}

/// The scan of planar (`D = 2`) or 3-D point sets in 8-lane AVX-512 vectors: a compare into a
/// mask register and two masked moves per minimum where AVX2 needs four operations, on twice the
/// lanes. `from` and `to` are not empty.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn nearest_avx512<const D: usize, const COLS: bool>(
    simd: pulp::x86::V4,
    from: &[f64],
    to: &[f64],
) -> NearestBoth {
    let f = simd.avx512f;
    let (n, m) = (from.len() / D, to.len() / D);
    let init = Block512::<D> {
        c: [f._mm512_setzero_pd(); D],
        v: f._mm512_set1_pd(f64::INFINITY),
        i: f._mm512_setzero_si512(),
    };
    let mut stack = [init; STACK_POINTS / 8];
    let mut heap = Vec::new();
    let blocks = m.div_ceil(8);
    let cols: &mut [Block512<D>] = if blocks <= stack.len() {
        &mut stack[..blocks]
    } else {
        heap.resize(blocks, init);
        &mut heap
    };
    for (blk, q) in cols.iter_mut().zip(to.chunks(8 * D)) {
        // NaN padding: its distances compare false, so padded lanes never hold a minimum.
        let mut c = [[f64::NAN; 8]; D];
        for (l, p) in q.chunks_exact(D).enumerate() {
            for a in 0..D {
                c[a][l] = p[a];
            }
        }
        for a in 0..D {
            blk.c[a] = pulp::cast(c[a]);
        }
    }
    let mut rows = vec![(0, 0.0); n];
    let mut groups = from
        .chunks_exact(D * GROUP)
        .zip(rows.chunks_exact_mut(GROUP));
    for (g, (p, out)) in groups.by_ref().enumerate() {
        rows_avx512::<D, GROUP, COLS>(simd, p, GROUP * g, cols, out);
    }
    let i0 = n - n % GROUP;
    let (p, out) = (&from[D * i0..], &mut rows[i0..]);
    match n % GROUP {
        0 => {}
        1 => rows_avx512::<D, 1, COLS>(simd, p, i0, cols, out),
        2 => rows_avx512::<D, 2, COLS>(simd, p, i0, cols, out),
        _ => rows_avx512::<D, 3, COLS>(simd, p, i0, cols, out),
    }
    let mut back = vec![(0, 0.0); if COLS { m } else { 0 }];
    for (blk, out) in cols.iter().zip(back.chunks_mut(8)) {
        let (v, i): ([f64; 8], [i64; 8]) = (pulp::cast(blk.v), pulp::cast(blk.i));
        for (o, (&v, &i)) in out.iter_mut().zip(v.iter().zip(&i)) {
            *o = (i as usize, v);
        }
    }
    (rows, back)
}

/// Rows `i0 .. i0 + R` (the points of `p`, `R` ≤ 4) against every block of eight, their minima
/// kept in registers and reduced across lanes together at the end.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn rows_avx512<const D: usize, const R: usize, const COLS: bool>(
    simd: pulp::x86::V4,
    p: &[f64],
    i0: usize,
    cols: &mut [Block512<D>],
    out: &mut [(usize, f64)],
) {
    let f = simd.avx512f;
    let zero = f._mm512_setzero_pd();
    let (mut pc, mut row) = ([[zero; D]; R], [f._mm512_setzero_si512(); R]);
    for r in 0..R {
        for a in 0..D {
            pc[r][a] = f._mm512_set1_pd(p[D * r + a]);
        }
        row[r] = f._mm512_set1_epi64((i0 + r) as i64);
    }
    let mut best_v = [f._mm512_set1_pd(f64::INFINITY); R];
    let mut best_j = [f._mm512_setzero_si512(); R];
    let mut j: __m512i = pulp::cast([0i64, 1, 2, 3, 4, 5, 6, 7]);
    for blk in cols.iter_mut() {
        let (mut cv, mut ci) = (blk.v, blk.i);
        for r in 0..R {
            // Summed in coordinate order, without FMA: the plain scan's bits.
            let dx = f._mm512_sub_pd(blk.c[0], pc[r][0]);
            let mut d = f._mm512_mul_pd(dx, dx);
            for a in 1..D {
                let t = f._mm512_sub_pd(blk.c[a], pc[r][a]);
                d = f._mm512_add_pd(d, f._mm512_mul_pd(t, t));
            }
            let better = f._mm512_cmp_pd_mask::<_CMP_LT_OQ>(d, best_v[r]);
            best_v[r] = f._mm512_mask_mov_pd(best_v[r], better, d);
            best_j[r] = f._mm512_mask_mov_epi64(best_j[r], better, j);
            if COLS {
                // Rows come in increasing order: strict `<` keeps the first on ties.
                let better = f._mm512_cmp_pd_mask::<_CMP_LT_OQ>(d, cv);
                cv = f._mm512_mask_mov_pd(cv, better, d);
                ci = f._mm512_mask_mov_epi64(ci, better, row[r]);
            }
        }
        if COLS {
            (blk.v, blk.i) = (cv, ci);
        }
        j = f._mm512_add_epi64(j, f._mm512_set1_epi64(8));
    }
    // Each lane kept its first minimum; across lanes the lowest index among equal minima wins.
    // Lanes never updated hold (0, ∞), the plain scan's answer when nothing is below ∞.
    let inf = f._mm512_set1_pd(f64::INFINITY);
    let mut v4 = [inf; 4];
    v4[..R].copy_from_slice(&best_v);
    let min = min4_pd(simd, v4);
    let mut at_min = [f._mm512_setzero_si512(); 4];
    for r in 0..R {
        let lane = f._mm512_set1_epi64(2 * r as i64);
        let at = f._mm512_cmp_pd_mask::<_CMP_EQ_OQ>(best_v[r], f._mm512_permutexvar_pd(lane, min));
        at_min[r] = f._mm512_mask_blend_epi64(at, f._mm512_set1_epi64(i64::MAX), best_j[r]);
    }
    let first: [i64; 8] = pulp::cast(min4_epi64(simd, at_min));
    let min: [f64; 8] = pulp::cast(min);
    for (r, o) in out.iter_mut().enumerate().take(R) {
        *o = (first[2 * r] as usize, min[2 * r]);
    }
}

/// The minimum of each of four vectors, in lanes 2r and 2r + 1: 11 shuffles and minima for the
/// four, where reducing each alone takes 6 and leaves four results to gather.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn min4_pd(simd: pulp::x86::V4, v: [__m512d; 4]) -> __m512d {
    let f = simd.avx512f;
    // Lanes 0–3 of a and b against lanes 4–7; then pairs; then within pairs.
    let ab = f._mm512_min_pd(
        f._mm512_shuffle_f64x2::<0b01_00_01_00>(v[0], v[1]),
        f._mm512_shuffle_f64x2::<0b11_10_11_10>(v[0], v[1]),
    );
    let cd = f._mm512_min_pd(
        f._mm512_shuffle_f64x2::<0b01_00_01_00>(v[2], v[3]),
        f._mm512_shuffle_f64x2::<0b11_10_11_10>(v[2], v[3]),
    );
    let q = f._mm512_min_pd(
        f._mm512_shuffle_f64x2::<0b10_00_10_00>(ab, cd),
        f._mm512_shuffle_f64x2::<0b11_01_11_01>(ab, cd),
    );
    f._mm512_min_pd(q, f._mm512_permute_pd::<0b0101_0101>(q))
}

/// [`min4_pd`] of signed 64-bit lanes.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn min4_epi64(simd: pulp::x86::V4, v: [__m512i; 4]) -> __m512i {
    let f = simd.avx512f;
    let ab = f._mm512_min_epi64(
        f._mm512_shuffle_i64x2::<0b01_00_01_00>(v[0], v[1]),
        f._mm512_shuffle_i64x2::<0b11_10_11_10>(v[0], v[1]),
    );
    let cd = f._mm512_min_epi64(
        f._mm512_shuffle_i64x2::<0b01_00_01_00>(v[2], v[3]),
        f._mm512_shuffle_i64x2::<0b11_10_11_10>(v[2], v[3]),
    );
    let q = f._mm512_min_epi64(
        f._mm512_shuffle_i64x2::<0b10_00_10_00>(ab, cd),
        f._mm512_shuffle_i64x2::<0b11_01_11_01>(ab, cd),
    );
    f._mm512_min_epi64(q, f._mm512_shuffle_epi32::<0b01_00_11_10>(q))
}

/// The first nearest point among the lanes' minima (lane `l` of block `b` is point `4b + l`):
/// strict `<` per lane kept each lane's first minimum; across lanes the smallest index among
/// equal distances wins, as in a plain scan.
#[inline(always)]
fn reduce_lanes<const LANES: usize>(v: &[f64; LANES], b: &[f64; LANES], m: usize) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for l in 0..LANES {
        let j = b[l] as usize * LANES + l;
        if j < m && (v[l] < best.1 || (v[l] == best.1 && j < best.0)) {
            best = (j, v[l]);
        }
    }
    best
}

#[inline(always)]
fn nearest_soa_body<const D: usize, const COLS: bool>(from: &[f64], to: &[f64]) -> NearestBoth {
    const LANES: usize = 4;
    // Padding far away (squared distances stay finite) never wins against a real point.
    const FAR: f64 = 1e100;
    let (n, m) = (from.len() / D, to.len() / D);
    if n == 0 || m == 0 {
        return (
            vec![(0, f64::INFINITY); n],
            vec![(0, f64::INFINITY); if COLS { m } else { 0 }],
        );
    }
    let blocks = m.div_ceil(LANES);
    let mut cols = vec![[[FAR; LANES]; D]; blocks];
    for (j, q) in to.chunks_exact(D).enumerate() {
        for a in 0..D {
            cols[j / LANES][a][j % LANES] = q[a];
        }
    }
    // Column minima over the rows seen so far; rows come in increasing order, so strict `<`
    // keeps the first row on ties. (x − y)² = (y − x)² exactly, so the distances are those of
    // the reverse scan. Indices are kept as f64 (exact below 2⁵³): same-width blends vectorise.
    let mut col_v = vec![[f64::INFINITY; LANES]; if COLS { blocks } else { 0 }];
    let mut col_i = vec![[0.0f64; LANES]; if COLS { blocks } else { 0 }];
    let mut rows = Vec::with_capacity(n);
    for (i, p) in from.chunks_exact(D).enumerate() {
        let row = i as f64;
        let mut best_v = [f64::INFINITY; LANES];
        let mut best_b = [0.0f64; LANES];
        for (b, blk) in cols.iter().enumerate() {
            let mut d = [0.0f64; LANES];
            for a in 0..D {
                for l in 0..LANES {
                    let t = blk[a][l] - p[a];
                    d[l] += t * t;
                }
            }
            let bf = b as f64;
            for l in 0..LANES {
                let better = d[l] < best_v[l];
                best_b[l] = if better { bf } else { best_b[l] };
                best_v[l] = if better { d[l] } else { best_v[l] };
            }
            if COLS {
                // On local copies: selects on memory are compiled to branches.
                let (mut v, mut x) = (col_v[b], col_i[b]);
                for l in 0..LANES {
                    let better = d[l] < v[l];
                    x[l] = if better { row } else { x[l] };
                    v[l] = if better { d[l] } else { v[l] };
                }
                (col_v[b], col_i[b]) = (v, x);
            }
        }
        rows.push(reduce_lanes(&best_v, &best_b, m));
    }
    let mut back = Vec::with_capacity(if COLS { m } else { 0 });
    if COLS {
        for j in 0..m {
            back.push((
                col_i[j / LANES][j % LANES] as usize,
                col_v[j / LANES][j % LANES],
            ));
        }
    }
    (rows, back)
}

/// Symmetric chamfer distance: mean nearest-neighbour distance, averaged over both directions.
#[cfg(test)]
pub(crate) fn chamfer(a: &[f64], b: &[f64], dim: usize) -> f64 {
    let (ab, ba) = nearest_both(a, b, dim);
    chamfer_of(&ab, &ba)
}

/// The chamfer distance from the nearest neighbours both ways (squared distances).
fn chamfer_of(ab: &[(usize, f64)], ba: &[(usize, f64)]) -> f64 {
    let m1 = ab.iter().map(|x| x.1.sqrt()).sum::<f64>() / ab.len() as f64;
    let m2 = ba.iter().map(|x| x.1.sqrt()).sum::<f64>() / ba.len() as f64;
    0.5 * (m1 + m2)
}

/// Least-squares affine map sending `src[i]` to `dst[j]` over the given `(i, j)` pairs.
/// `None` when the pairs do not determine an affine map (fewer than `dim + 1` points in general
/// position) or `dim` is not 2 or 3.
pub fn fit_affine(
    src: &[f64],
    dst: &[f64],
    dim: usize,
    pairs: &[(usize, usize)],
) -> Option<Affine> {
    let d1 = dim + 1;
    if pairs.len() < d1 {
        return None;
    }
    let (ata, atb) = match dim {
        // Fixed sizes unroll: this runs for every pass of every ICP start.
        2 => normal_equations::<2>(src, dst, pairs),
        3 => normal_equations::<3>(src, dst, pairs),
        _ => return None,
    };
    let w = crate::geometry::solve_normal_equations(&ata, &atb, dim)?;
    let mut aff = Affine::identity(dim);
    for a in 0..dim {
        for b in 0..dim {
            aff.m[a][b] = w[b][a];
        }
        aff.t[a] = w[dim][a];
    }
    let ok = aff
        .m
        .iter()
        .flatten()
        .chain(aff.t.iter())
        .all(|v| v.is_finite());
    ok.then_some(aff)
}

/// Normal equations of the affine least-squares fit in homogeneous coordinates:
/// `(Σ x̃ x̃ᵀ) W = Σ x̃ yᵀ`, `x̃ = (x, 1)`.
fn normal_equations<const D: usize>(
    src: &[f64],
    dst: &[f64],
    pairs: &[(usize, usize)],
) -> ([[f64; 4]; 4], [[f64; 3]; 4]) {
    let mut ata = [[0.0; 4]; 4];
    let mut atb = [[0.0; 3]; 4];
    for &(i, j) in pairs {
        let mut x = [1.0; 4];
        x[..D].copy_from_slice(&src[i * D..(i + 1) * D]);
        let y = &dst[j * D..(j + 1) * D];
        for r in 0..=D {
            for c in 0..=D {
                ata[r][c] += x[r] * x[c];
            }
            for c in 0..D {
                atb[r][c] += x[r] * y[c];
            }
        }
    }
    (ata, atb)
}

/// Symmetric affine ICP from `start`: nearest neighbours in both directions, least-squares affine
/// fit, `iters` times. Returns the final map and the chamfer distance it reaches. Maps that reflect
/// (negative determinant) are refused when `keep_orientation` is set, so contours stay
/// counter-clockwise.
pub(crate) fn icp_affine(
    a: &[f64],
    b: &[f64],
    dim: usize,
    start: Affine,
    iters: usize,
    keep_orientation: bool,
) -> (Affine, f64) {
    let mut cur = start;
    let mut moved = cur.apply(a);
    let mut it = 0;
    loop {
        // The neighbours of the current position serve both the next fit and the final score.
        let (ab, ba) = nearest_both(&moved, b, dim);
        if it == iters {
            return (cur, chamfer_of(&ab, &ba));
        }
        it += 1;
        let mut pairs: Vec<(usize, usize)> = ab.iter().enumerate().map(|(i, x)| (i, x.0)).collect();
        pairs.extend(ba.iter().enumerate().map(|(j, x)| (x.0, j)));
        let Some(step) = fit_affine(&moved, b, dim, &pairs) else {
            return (cur, chamfer_of(&ab, &ba));
        };
        let next = step.compose(&cur);
        if keep_orientation && next.det() <= 0.0 {
            return (cur, chamfer_of(&ab, &ba));
        }
        // Converged: the pairs would not change any more.
        let still = step.is_within_of_identity(1e-9);
        cur = next;
        moved = cur.apply(a);
        if still {
            it = iters;
        }
    }
}

/// Rotation candidates mapping A's normalised frame into B's (docs/method.md §7.1): the identity,
/// `V_b · diag(s) · V_aᵀ` for every proper sign pattern `s`, and each of those turned by 90° about
/// B's last principal axis; then, when `turns > 1`, the turns by `2πk / turns` (k = 1 … turns − 1)
/// about the same axis.
pub(crate) fn rotation_candidates(a: &[f64], b: &[f64], dim: usize, turns: usize) -> Vec<Affine> {
    let (va, _) = principal_axes(a, dim);
    let (vb, _) = principal_axes(b, dim);
    let signs: Vec<[f64; 3]> = if dim == 2 {
        vec![[1.0, 1.0, 1.0], [-1.0, -1.0, 1.0]]
    } else {
        vec![
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ]
    };
    // 90° turn in the plane of the first two principal axes.
    let turn = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let mut out = vec![Affine::identity(dim)];
    for quarter in [false, true] {
        for s in &signs {
            // R = V_b · T · diag(s) · V_aᵀ
            let mut inner = [[0.0; 3]; 3];
            for r in 0..3 {
                for c in 0..3 {
                    let t = if quarter {
                        turn[r][c]
                    } else if r == c {
                        1.0
                    } else {
                        0.0
                    };
                    inner[r][c] = t * s[c];
                }
            }
            out.push(Affine::linear(
                dim,
                crate::geometry::sandwich(dim, &vb, &inner, &va),
            ));
        }
    }
    for k in 1..turns {
        // R = V_b · Rz(θ) · V_bᵀ: a turn in the plane of B's first two principal axes (in 2-D
        // simply the rotation by θ).
        let rz = crate::geometry::rotation_z(std::f64::consts::TAU * k as f64 / turns as f64);
        out.push(Affine::linear(
            dim,
            crate::geometry::sandwich(dim, &vb, &rz, &vb),
        ));
    }
    out
}

/// How [`robust_prealign`] searches the rotation between two objects.
///
/// Affine ICP has many local minima on rounded outlines, a few degrees apart; a start has to fall
/// within about 10° of the true turn to reach it, and the chamfer only ranks the minima correctly
/// once ICP has converged. So many evenly spaced starts are screened with a few iterations, and
/// the best of them (the identity always among them) are run to convergence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotationSearch {
    /// Evenly spaced starting turns (every `360° / turns`) added to the identity and the
    /// principal-axes candidates; 0 or 1 adds none (the five principal-axes candidates only).
    pub turns: usize,
    /// ICP iterations every start gets before the screening.
    pub screen_iterations: usize,
    /// Starts refined after the screening: the identity and the best-scoring others.
    pub survivors: usize,
    /// ICP iterations of a survivor in all; fewer when its pairs stop changing.
    pub iterations: usize,
    /// The motion prior: refined candidates whose chamfer distance is within this fraction of
    /// the best one's fit nearly as well, and the one with the smallest turn among them wins
    /// (see [`select_candidate`]). Every turn of a nearly round outline fits about as well as
    /// the true one, and an ellipse fits itself turned by 180°.
    pub tolerance: f64,
    /// The largest turn in degrees (of the rotation part of the map, see [`rotation_angle`]) a
    /// candidate may have; `None`: any. Starts that cannot reach it are not refined.
    pub max_rotation: Option<f64>,
    /// For two closed planar outlines: point-to-line affine ICP steps after each survivor's node
    /// ICP, which fit the outlines rather than their nodes (at most; fewer once converged); the
    /// survivors whose fitted outlines lie clearly further apart than the closest are then out
    /// of the choice. 0: none (the survivors' node fits, chosen by their chamfer).
    pub outline_iterations: usize,
    /// When the outline fit ends the search: the most nodes of either outline the screening's
    /// ICP runs on; a larger outline lends it every `s`-th node only, `s = ⌈n / limit⌉`. The
    /// survivors converge, and are chosen, on every node. `None`: every node.
    pub screen_node_limit: Option<usize>,
}

impl Default for RotationSearch {
    /// Measured on severe ground-truth contour pairs, before the outline fit: 210 of
    /// bench_match.py (seeds 1–7) 0.925 with the five principal-axes candidates, 0.976 with
    /// these; the Rust tests' 90: 0.921 vs 0.966. Fewer turns (16–30) or a single screening
    /// iteration lost 0.01–0.03 of that. Ten outline-fit steps then take them to 0.980 and 0.976
    /// (more steps change nothing: the point-to-line steps converge in a few).
    fn default() -> Self {
        Self {
            turns: 36,
            screen_iterations: 2,
            survivors: 4,
            iterations: 20,
            tolerance: NEAR_TIE,
            max_rotation: None,
            outline_iterations: 10,
            screen_node_limit: Some(SCREEN_NODE_LIMIT),
        }
    }
}

/// The default [`RotationSearch::screen_node_limit`]. The screening only ranks the starts, to
/// pick the few that converge; where the affine fit's minima lie (a few degrees apart on rounded
/// outlines) is the shape's, not its sampling's. The search was measured on outlines of 48–78
/// nodes (bench_match.py and the Rust ground truth, which this leaves unchanged); a larger
/// outline is screened at that density, since the screening's nearest-neighbour scans grow with
/// the product of the two counts, and its survivors still converge on every node.
pub const SCREEN_NODE_LIMIT: usize = 80;

/// The nodes of `pts` the screening's ICP runs on (see [`RotationSearch::screen_node_limit`]):
/// every node unless the outline fit ends the search (`outlines`) and the object has more than
/// the limit.
pub(crate) fn screen_nodes<'p>(
    pts: &'p [f64],
    dim: usize,
    search: &RotationSearch,
    outlines: bool,
) -> Cow<'p, [f64]> {
    let n = pts.len() / dim;
    match search.screen_node_limit {
        Some(limit) if outlines && n > limit.max(1) => {
            let stride = n.div_ceil(limit.max(1));
            Cow::Owned(
                pts.chunks_exact(dim)
                    .step_by(stride)
                    .flatten()
                    .copied()
                    .collect(),
            )
        }
        _ => Cow::Borrowed(pts),
    }
}

/// The default [`RotationSearch::tolerance`]: 0.1 %, the earlier rule's tie margin (which only
/// the identity start could win). Looser margins were tried: the refined chamfers of different
/// turns are close — an outline (tests' ellipse) turned by 115° scores 0.0270 at the true turn
/// and 0.0281 at the identity after affine ICP (4 % apart), and at 2 % a three-lobed round
/// outline turned by 15° was matched at a 9° neighbour. So the margin stays a tie margin, and
/// consecutive frames are protected by the bound ([`RotationSearch::max_rotation`]) instead.
pub const NEAR_TIE: f64 = 1e-3;

impl RotationSearch {
    /// The five principal-axes starts only: identity and principal-axes candidates, `iterations`
    /// ICP each.
    pub fn spec(iterations: usize) -> Self {
        Self {
            turns: 0,
            screen_iterations: iterations,
            survivors: usize::MAX,
            iterations,
            ..Self::default()
        }
    }

    /// ICP iterations every start gets before the screening ranks them (at most `iterations`).
    pub(crate) fn screening_iterations(&self) -> usize {
        self.screen_iterations.min(self.iterations)
    }
}

/// Starts screened per rayon task: one start's two ICP iterations take ~10 µs, too little to be
/// a task of its own.
const SCREEN_CHUNK: usize = 8;

/// The robust pre-alignment of docs/method.md §7.1: rotation candidates refined by symmetric affine
/// ICP and scored by chamfer distance, searched as `search` says; the identity wins ties (within
/// 0.1 %), because every turn of a nearly round outline scores about the same.
pub fn robust_prealign(
    a: &[f64],
    b: &[f64],
    dim: usize,
    search: &RotationSearch,
    keep_orientation: bool,
) -> Affine {
    search_run(a, b, dim, search, keep_orientation, true)
}

/// The whole search between `a` and `b`, on the rayon pool (`parallel`) or on the calling
/// thread.
fn search_run(
    a: &[f64],
    b: &[f64],
    dim: usize,
    search: &RotationSearch,
    keep_orientation: bool,
    parallel: bool,
) -> Affine {
    let outlines = fits_outlines(dim, search, keep_orientation);
    let (a_screen, b_screen) = (
        screen_nodes(a, dim, search, outlines),
        screen_nodes(b, dim, search, outlines),
    );
    let pair = SearchPair {
        a,
        b,
        a_screen: &a_screen,
        b_screen: &b_screen,
        dim,
        search,
        keep_orientation,
    };
    pair.run(parallel)
}

/// Two objects' normalised points and the rotation search between them: what every stage of
/// the search reads.
#[derive(Clone, Copy)]
pub(crate) struct SearchPair<'a> {
    pub a: &'a [f64],
    pub b: &'a [f64],
    /// The nodes of A and B the screening runs on ([`screen_nodes`]).
    pub a_screen: &'a [f64],
    pub b_screen: &'a [f64],
    pub dim: usize,
    pub search: &'a RotationSearch,
    /// No map that reflects (ordered outlines).
    pub keep_orientation: bool,
}

/// A survivor of the screening run to convergence: its node fit `(map, chamfer)` and, for two
/// closed planar outlines, its outline fit `(map, outline distance)`.
pub(crate) type SurvivorFit = ((Affine, f64), Option<(Affine, f64)>);

/// The screened starts that run to convergence, as indices into `screened` in the order
/// [`SearchPair::choose`] expects them ([`survivor_order`]); `None` when the screening already
/// ran every iteration.
pub(crate) fn survivors(screened: &[(Affine, f64)], search: &RotationSearch) -> Option<Vec<usize>> {
    (search.iterations > search.screening_iterations()).then(|| survivor_order(screened, search))
}

impl SearchPair<'_> {
    /// The whole search: every start screened, then [`SearchPair::finish`]; on the rayon pool
    /// (`parallel`) or on the calling thread, the same map either way.
    fn run(&self, parallel: bool) -> Affine {
        let starts = self.starts();
        // The starts are independent. `collect` keeps the candidates' order, so the result does
        // not depend on the scheduling.
        let screened: Vec<(Affine, f64)> = if parallel {
            starts
                .into_par_iter()
                .with_min_len(SCREEN_CHUNK)
                .map(|c| self.screen(c))
                .collect()
        } else {
            starts.into_iter().map(|c| self.screen(c)).collect()
        };
        self.finish(&screened, parallel)
    }

    /// The starting maps of the search, in the order every stage keeps
    /// ([`rotation_candidates`]).
    pub(crate) fn starts(&self) -> Vec<Affine> {
        rotation_candidates(self.a, self.b, self.dim, self.search.turns)
    }

    /// One start screened: its first ICP iterations and the chamfer they reach.
    pub(crate) fn screen(&self, start: Affine) -> (Affine, f64) {
        let iters = self.search.screening_iterations();
        icp_affine(
            self.a_screen,
            self.b_screen,
            self.dim,
            start,
            iters,
            self.keep_orientation,
        )
    }

    /// The search after the screening: the survivors of the screened starts ([`survivors`]) run
    /// to convergence ([`SearchPair::converge`]), on the rayon pool (`parallel`) or on the
    /// calling thread, and the best of them wins ([`SearchPair::choose`]). The same map either
    /// way.
    pub(crate) fn finish(&self, screened: &[(Affine, f64)], parallel: bool) -> Affine {
        let run = |&i: &usize| self.converge(screened[i].0);
        let fits: Option<Vec<SurvivorFit>> = survivors(screened, self.search).map(|order| {
            if parallel {
                order.par_iter().map(run).collect()
            } else {
                order.iter().map(run).collect()
            }
        });
        self.choose(screened, fits.as_deref())
    }

    /// Whether the search ends with the outline fit: two closed planar outlines, and steps
    /// asked for.
    fn fits_outlines(&self) -> bool {
        fits_outlines(self.dim, self.search, self.keep_orientation)
    }

    /// One survivor from its screened map `start`: the remaining node ICP iterations, then, for
    /// two closed outlines, the outline fit and the distance of the fitted outlines.
    pub(crate) fn converge(&self, start: Affine) -> SurvivorFit {
        let (a, b) = (self.a, self.b);
        let remaining = self.search.iterations - self.search.screening_iterations();
        let node_fit = icp_affine(a, b, self.dim, start, remaining, self.keep_orientation);
        let outline_fit = self.fits_outlines().then(|| {
            let steps = self.search.outline_iterations;
            let fitted = outline_fit::fit_outlines(a, b, node_fit.0, steps);
            (fitted, outline_fit::outline_distance(&fitted.apply(a), b))
        });
        (node_fit, outline_fit)
    }

    /// The search's map from the screened starts and the survivors' fits (`None`: the screening
    /// ran every iteration, and the screened starts are the candidates). Two closed planar
    /// outlines choose among the survivors whose fitted outlines lie about as close as the
    /// closest do ([`closest_outlines`]); the others by [`select_candidate`].
    pub(crate) fn choose(
        &self,
        screened: &[(Affine, f64)],
        fits: Option<&[SurvivorFit]>,
    ) -> Affine {
        let (dim, search) = (self.dim, self.search);
        let outlines = self.fits_outlines();
        let Some(fits) = fits else {
            let picked = select_candidate(screened, dim, search);
            return if outlines {
                outline_fit::fit_outlines(self.a, self.b, picked, search.outline_iterations)
            } else {
                picked
            };
        };
        let node_fits: Vec<(Affine, f64)> = fits.iter().map(|c| c.0).collect();
        if !outlines {
            return select_candidate(&node_fits, dim, search);
        }
        let outline_fits: Vec<(Affine, f64)> = fits.iter().filter_map(|c| c.1).collect();
        let closest = closest_outlines(&outline_fits, search);
        let contenders: Vec<(Affine, f64)> = closest.iter().map(|&k| node_fits[k]).collect();
        select_index(&contenders, search).map_or_else(
            || Affine::identity(dim),
            |j| self.least_turn_alike(outline_fits[closest[j]]),
        )
    }

    /// The chosen outline fit `(map, outline distance)`, or, when it turns by more than
    /// [`TURN_BACK_ABOVE`], the fit of smallest turn among the chosen one's quarter turns (each
    /// run to convergence from the chosen map turned by 90°, 180° and 270°) whose outlines lie
    /// within [`TURN_BACK_MARGIN`] of the chosen one's.
    ///
    /// A nearly symmetric outline (an ellipse, a grain, a fish) fits itself turned by a half
    /// turn about as well; the survivors of the screening may then hold no fit near the small
    /// turn, or only one stuck in a poorer local minimum of the affine ICP, and the half turn
    /// wins. Turning the winning fit back and converging it gives the small turn a fit as good
    /// as the winner's, and the motion prior decides between fits that good.
    fn least_turn_alike(&self, chosen: (Affine, f64)) -> Affine {
        if rotation_angle(&chosen.0) <= TURN_BACK_ABOVE {
            return chosen.0;
        }
        let bound = self.search.max_rotation.unwrap_or(f64::INFINITY);
        let near = chosen.1 * (1.0 + TURN_BACK_MARGIN) + EXACT_FIT;
        let mut best = (chosen.0, rotation_angle(&chosen.0));
        for quarter in 1..4 {
            let turn = crate::geometry::rotation_z(std::f64::consts::FRAC_PI_2 * quarter as f64);
            let start = Affine::linear(2, turn).compose(&chosen.0);
            let Some((fit, distance)) = self.converge(start).1 else {
                continue;
            };
            let angle = rotation_angle(&fit);
            if distance <= near && angle <= bound && angle < best.1 {
                best = (fit, angle);
            }
        }
        best.0
    }
}

/// Whether the search ends with the outline fit: two closed planar outlines (`keep_orientation`),
/// and steps asked for.
pub(crate) fn fits_outlines(dim: usize, search: &RotationSearch, keep_orientation: bool) -> bool {
    keep_orientation && dim == 2 && search.outline_iterations > 0
}

/// The survivors whose fitted outlines lie within [`OUTLINE_MARGIN`] of the closest
/// ([`outline_fit::outline_distance`]; among those within the rotation bound, if any).
///
/// The chamfer of the nodes ranks a nearly round outline's fits poorly: two samplings of one
/// curve keep their nodes apart even at the true map, and a far turn can snap them closer.
/// Severe heel strikes (turned by 17-34°) were matched at 0 % by turns of 93-162° whose fitted
/// outlines lay clearly further from B than the true turn's. Where the outlines cannot tell
/// fits apart (an ellipse fits its affine images at any turn) the nodes still decide.
fn closest_outlines(fits: &[(Affine, f64)], search: &RotationSearch) -> Vec<usize> {
    let turn: Vec<f64> = fits.iter().map(|c| rotation_angle(&c.0)).collect();
    let mut pool = within_bound(fits, &turn, search);
    if pool.is_empty() {
        pool = (0..fits.len()).collect();
    }
    let best = pool
        .iter()
        .map(|&k| fits[k].1)
        .fold(f64::INFINITY, f64::min);
    let near = best * (1.0 + OUTLINE_MARGIN) + EXACT_FIT;
    pool.retain(|&k| fits[k].1 <= near);
    if pool.is_empty() {
        // No distance is finite (the fits failed): the nodes decide alone.
        pool = (0..fits.len()).collect();
    }
    pool
}

/// How much further than the closest fitted outlines a survivor's may lie and still be chosen
/// by its nodes (a fraction). On 810 severe pairs of bench_match.py's held-out generator (seeds
/// 1001-1003 and 1010-1015) any margin from 0.02 to 0.5 chose the same maps: the far turns'
/// outlines lie more than 1.5 times as far.
const OUTLINE_MARGIN: f64 = 0.1;

/// Outline distances below this (mean squared, in B's normalised frame whose RMS radius is 1)
/// are as close as the outline fit's steps come: [`closest_outlines`] treats them as equal. Two
/// samplings of a real outline lie further apart (at least 1.8e-6 on 108 ground-truth pairs);
/// an outline and its exact affine image end at about 1e-8 or below.
const EXACT_FIT: f64 = 1e-9;

/// A chosen turn beyond this (degrees) is checked against its quarter turns
/// ([`SearchPair::least_turn_alike`]). Above the severe ground-truth turns (at most 35°): none
/// of bench_match.py's 1,080 held-out pairs of seeds 1, 4, 5 and 6 changed.
const TURN_BACK_ABOVE: f64 = 45.0;

/// How much further than the chosen fit's outlines a quarter turn's may lie and still win by its
/// smaller turn (a fraction: 1 is twice as far). On the 144 tuning pairs of bench_landmarks.py
/// (real outlines of one class, 15 chosen half turns or quarter turns away from the landmarks'
/// turn) 0.1 turned 8 of them back, 0.3 11, 1 13 and 2 14.
const TURN_BACK_MARGIN: f64 = 1.0;

/// The screened starts that run to convergence: the identity (index 0), whatever its score (see
/// [`select_candidate`]), then the best-scoring others that can still end within
/// [`RotationSearch::max_rotation`], `survivors` in all.
fn survivor_order(screened: &[(Affine, f64)], search: &RotationSearch) -> Vec<usize> {
    // A screened start more than one start spacing beyond the bound will not come back within it.
    let reach = search
        .max_rotation
        .map_or(f64::INFINITY, |m| m + 360.0 / search.turns.max(4) as f64);
    let mut order: Vec<usize> = (1..screened.len())
        .filter(|&i| rotation_angle(&screened[i].0) <= reach)
        .collect();
    order.sort_by(|&x, &y| screened[x].1.total_cmp(&screened[y].1));
    order.truncate(search.survivors.saturating_sub(1));
    order.insert(0, 0);
    order
}

/// The candidate the pre-alignment keeps, from refined `(map, chamfer)` pairs: the motion prior.
/// Candidates turning by more than [`RotationSearch::max_rotation`] are out (if every one is,
/// the one turning least is kept); among the rest, those whose chamfer is within
/// [`RotationSearch::tolerance`] of the best fit nearly as well, and of them the one with the
/// smallest turn wins (the first on ties). So a nearly round or symmetric outline keeps the
/// small turn that fits it, not a far one that happens to fit marginally better.
pub fn select_candidate(cands: &[(Affine, f64)], dim: usize, search: &RotationSearch) -> Affine {
    select_index(cands, search).map_or_else(|| Affine::identity(dim), |k| cands[k].0)
}

/// The index of [`select_candidate`]'s choice (`None` for no candidates).
fn select_index(cands: &[(Affine, f64)], search: &RotationSearch) -> Option<usize> {
    let turn: Vec<f64> = cands.iter().map(|c| rotation_angle(&c.0)).collect();
    let least_turn = |ks: &mut dyn Iterator<Item = usize>| {
        ks.min_by(|&x, &y| turn[x].total_cmp(&turn[y]).then(x.cmp(&y)))
    };
    let allowed = within_bound(cands, &turn, search);
    if allowed.is_empty() {
        return least_turn(&mut (0..cands.len()));
    }
    let best = allowed
        .iter()
        .map(|&k| cands[k].1)
        .fold(f64::INFINITY, f64::min);
    let near = best * (1.0 + search.tolerance.max(0.0));
    least_turn(&mut allowed.into_iter().filter(|&k| cands[k].1 <= near))
}

/// The candidates with a finite score that turn (`turn`, their [`rotation_angle`]s) no further
/// than [`RotationSearch::max_rotation`].
fn within_bound(cands: &[(Affine, f64)], turn: &[f64], search: &RotationSearch) -> Vec<usize> {
    let bound = search.max_rotation.unwrap_or(f64::INFINITY);
    (0..cands.len())
        .filter(|&k| turn[k] <= bound && cands[k].1.is_finite())
        .collect()
}

/// The turn of an affine map in degrees, in [0, 180]: the angle of the rotation `R` of its polar
/// decomposition `M = R S` (`S` symmetric positive semi-definite), i.e. the nearest rotation.
/// A map that reflects reports the turn of its nearest rotation times the reflection.
pub fn rotation_angle(aff: &Affine) -> f64 {
    let m = &aff.m;
    if aff.dim == 2 {
        // For M = R(θ) S with S symmetric: m10 − m01 = sin θ · tr S, m00 + m11 = cos θ · tr S.
        return (m[1][0] - m[0][1])
            .atan2(m[0][0] + m[1][1])
            .abs()
            .to_degrees();
    }
    let r = nearest_rotation3(m);
    let trace = r[0][0] + r[1][1] + r[2][2];
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

/// The orthogonal factor of the polar decomposition of a 3×3 matrix by Newton's iteration
/// `R ← (R + R⁻ᵀ) / 2` (quadratic convergence; a handful of steps for the maps ICP produces).
fn nearest_rotation3(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut r = *m;
    for _ in 0..30 {
        let det = Affine::linear(3, r).det();
        if !(det.is_finite() && det.abs() > 1e-300) {
            break;
        }
        // R⁻ᵀ = cofactor matrix / det.
        let cof = |a: usize, b: usize| {
            let (a1, a2) = ((a + 1) % 3, (a + 2) % 3);
            let (b1, b2) = ((b + 1) % 3, (b + 2) % 3);
            r[a1][b1] * r[a2][b2] - r[a1][b2] * r[a2][b1]
        };
        let mut next = [[0.0; 3]; 3];
        let mut change = 0.0f64;
        for a in 0..3 {
            for b in 0..3 {
                next[a][b] = 0.5 * (r[a][b] + cof(a, b) / det);
                change = change.max((next[a][b] - r[a][b]).abs());
            }
        }
        r = next;
        if change < 1e-12 {
            break;
        }
    }
    r
}

/// [`robust_prealign`] on the calling thread only: the same candidates in the same order, so the
/// same map.
pub(crate) fn robust_prealign_serial(
    a: &[f64],
    b: &[f64],
    dim: usize,
    search: &RotationSearch,
    keep_orientation: bool,
) -> Affine {
    search_run(a, b, dim, search, keep_orientation, false)
}

/// A's coordinates after an affine map into B's normalised frame. A closed outline resampled by
/// arc length has a centroid and RMS radius that hardly depend on where its points fall, so a
/// contour is normalised again, which removes the small bias the fit leaves. A random sampling's
/// centroid wanders by about radius / √n, more than the fit's error, so a point set keeps the
/// map's frame. Measured (bench_match.py): re-normalising point sets cut the nearest-neighbour
/// hits of aligned surfaces from 0.49 to 0.39; not re-normalising contours cost the
/// positions-only baseline 0.946 → 0.940 on 210 severe cases (the modal recipe: no change).
/// An affine map that collapses A is an error either way.
/// Also returns the map the re-normalisation applied (the identity for a point set).
pub(crate) fn into_b_frame(
    moved: Vec<f64>,
    d: usize,
    ordered: bool,
) -> Result<(Vec<f64>, Affine), ModalError> {
    let (normalised, centroid, scale) = normalize(&moved, d)?;
    Ok(if ordered {
        (
            normalised,
            crate::matching::prepare::normalizing_map(d, centroid, scale),
        )
    } else {
        (moved, Affine::identity(d))
    })
}

/// Stage 2: A in B's normalised frame after the pre-alignment's map `t` (none with
/// `Prealign::Normalize`), and the map from A's normalised frame to those coordinates. `ordered`
/// asks for the re-normalisation of [`into_b_frame`] (see [`Prealign::renormalizes`]).
pub(crate) fn start_in_b_frame(
    a: &[f64],
    t: Option<Affine>,
    d: usize,
    ordered: bool,
) -> Result<(Vec<f64>, Affine), ModalError> {
    match t {
        Some(t) => into_b_frame(t.apply(a), d, ordered)
            .map(|(cur, renormalize)| (cur, renormalize.compose(&t))),
        None => Ok((a.to_vec(), Affine::identity(d))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points of the closed curve `at(t)`, `t` from 0 round a turn, turned by `rot`.
    fn turned_curve(n: usize, rot: f64, at: impl Fn(f64) -> (f64, f64)) -> Vec<f64> {
        (0..n)
            .flat_map(|i| {
                let (x, y) = at(i as f64 / n as f64 * std::f64::consts::TAU);
                [rot.cos() * x - rot.sin() * y, rot.sin() * x + rot.cos() * y]
            })
            .collect()
    }

    fn ellipse(n: usize, rot: f64) -> Vec<f64> {
        turned_curve(n, rot, |t| {
            (2.0 * t.cos() + 0.3 * (2.0 * t).cos(), 0.8 * t.sin())
        })
    }

    /// Both-way and one-way results of every nearest-neighbour kernel this CPU can run.
    fn kernel_results<const D: usize>(
        a: &[f64],
        b: &[f64],
    ) -> Vec<(&'static str, NearestBoth, NearestBoth)> {
        let mut out = vec![(
            "portable",
            nearest_soa_body::<D, true>(a, b),
            nearest_soa_body::<D, false>(a, b),
        )];
        #[cfg(target_arch = "x86_64")]
        {
            use crate::simd::{on_avx2, on_avx512};
            if let Some(simd) = pulp::x86::V3::try_new() {
                let both = on_avx2(simd, NearestSoa::<D, true> { from: a, to: b });
                let one = on_avx2(simd, NearestSoa::<D, false> { from: a, to: b });
                out.push(("avx2", both, one));
            }
            if let Some(simd) = pulp::x86::V4::try_new() {
                let both = on_avx512(simd, NearestSoa::<D, true> { from: a, to: b });
                let one = on_avx512(simd, NearestSoa::<D, false> { from: a, to: b });
                out.push(("avx512", both, one));
            }
        }
        out
    }

    #[test]
    fn nearest_one_and_both_ways_match_a_plain_scan_with_ties() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Coarse values make exact distance ties common.
            ((seed >> 40) % 7) as f64 - 3.0
        };
        let plain = |from: &[f64], to: &[f64], dim: usize| -> Vec<(usize, f64)> {
            from.chunks_exact(dim)
                .map(|p| {
                    let mut best = (0, f64::INFINITY);
                    for (j, q) in to.chunks_exact(dim).enumerate() {
                        let d: f64 = (0..dim).map(|c| (p[c] - q[c]).powi(2)).sum();
                        if d < best.1 {
                            best = (j, d);
                        }
                    }
                    best
                })
                .collect()
        };
        let check = |a: &[f64], b: &[f64], dim: usize, what: &str| {
            let want = (plain(a, b, dim), plain(b, a, dim));
            assert_eq!(nearest(a, b, dim), want.0, "{what}");
            assert_eq!(nearest_both(a, b, dim), want, "both, {what}");
            let kernels = match dim {
                2 => kernel_results::<2>(a, b),
                3 => kernel_results::<3>(a, b),
                _ => vec![],
            };
            for (name, both, one) in kernels {
                assert_eq!(both, want, "{name}, {what}");
                assert_eq!(one, (want.0.clone(), vec![]), "{name} one way, {what}");
            }
        };
        // Every remainder of the planar kernels' groups of rows (n mod 4) and lanes (m mod 8),
        // empty sets, and contour-sized pairs.
        let sizes = (1..=9).flat_map(|n| (1..=17).map(move |m| (n, m))).chain([
            (20, 8),
            (3, 40),
            (0, 4),
            (4, 0),
            (60, 64),
            (64, 60),
            (130, 7),
        ]);
        for dim in 1..=4 {
            for (n, m) in sizes.clone() {
                let a: Vec<f64> = (0..n * dim).map(|_| rnd()).collect();
                let b: Vec<f64> = (0..m * dim).map(|_| rnd()).collect();
                check(&a, &b, dim, &format!("dim {dim}, {n}×{m}"));
            }
        }
        // NaN distances never count and infinite ones never beat the empty answer (0, ∞).
        let a = [0.0, 0.0, f64::NAN, 1.0, 1e200, 0.0, 2.0, 1.0, 3.0, f64::NAN];
        let b = [1.0, 1.0, -1e200, 5.0, 0.0, f64::NAN, 2.0, 1.0, 0.0, 0.0];
        check(&a, &b, 2, "NaN and overflow");
        check(&a[..6], &b[..2], 2, "NaN and overflow, 3×1");
        let (a3, b3) = (
            [0.0, 0.0, f64::NAN, 1.0, 1e200, 0.0, 2.0, 1.0, 3.0],
            [1.0, 1.0, -1e200, 5.0, 0.0, f64::NAN, 2.0, 1.0, 0.0],
        );
        check(&a3, &b3, 3, "NaN and overflow, 3-D");
        // Beyond the kernels' stack blocks.
        for dim in [2, 3] {
            let a: Vec<f64> = (0..dim * 70).map(|_| rnd()).collect();
            let b: Vec<f64> = (0..dim * 300).map(|_| rnd()).collect();
            check(&a, &b, dim, &format!("dim {dim}, 70×300"));
        }
        assert_eq!(nearest(&[0.0, 0.0], &[], 2), vec![(0, f64::INFINITY)]);
    }

    #[test]
    fn normalize_centres_and_scales() {
        let p = [1.0, 1.0, 3.0, 1.0, 3.0, 5.0];
        let (q, c, _) = normalize(&p, 2).unwrap();
        assert!((c[0] - 7.0 / 3.0).abs() < 1e-12);
        let rms: f64 = (q.iter().map(|v| v * v).sum::<f64>() / 3.0).sqrt();
        assert!((rms - 1.0).abs() < 1e-12);
        assert!(normalize(&[2.0, 2.0, 2.0, 2.0], 2).is_err());
    }

    #[test]
    fn sym_eigen3_reconstructs() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, -0.2], [0.5, -0.2, 1.0]];
        let (vals, v) = sym_eigen3(a);
        for r in 0..3 {
            for c in 0..3 {
                let s: f64 = (0..3).map(|k| v[r][k] * vals[k] * v[c][k]).sum();
                assert!((s - a[r][c]).abs() < 1e-10);
            }
        }
    }

    #[test]
    fn affine_fit_recovers_map() {
        let src = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 2.0, -1.0, 0.5];
        let truth = Affine {
            dim: 2,
            m: [[1.2, 0.3, 0.0], [-0.1, 0.9, 0.0], [0.0; 3]],
            t: [0.5, -2.0, 0.0],
        };
        let dst = truth.apply(&src);
        let pairs: Vec<_> = (0..5).map(|i| (i, i)).collect();
        let fit = fit_affine(&src, &dst, 2, &pairs).unwrap();
        for a in 0..2 {
            assert!((fit.t[a] - truth.t[a]).abs() < 1e-10);
            for b in 0..2 {
                assert!((fit.m[a][b] - truth.m[a][b]).abs() < 1e-10);
            }
        }
        // Collinear sources do not determine an affine map.
        let col = [0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 3.0, 3.0];
        assert!(fit_affine(&col, &col, 2, &[(0, 0), (1, 1), (2, 2), (3, 3)]).is_none());
        // 3-D, with pairs in a shuffled order and one destination used twice.
        let src3 = [
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 2.0, -1.0,
        ];
        let truth3 = Affine {
            dim: 3,
            m: [[1.1, 0.2, -0.3], [0.0, 0.8, 0.1], [0.4, -0.2, 1.3]],
            t: [0.5, -1.0, 2.0],
        };
        let mut dst3 = truth3.apply(&src3);
        dst3.extend_from_within(3..6);
        let pairs3 = [(4, 4), (1, 5), (0, 0), (3, 3), (2, 2), (1, 1)];
        let fit3 = fit_affine(&src3, &dst3, 3, &pairs3).unwrap();
        for a in 0..3 {
            assert!((fit3.t[a] - truth3.t[a]).abs() < 1e-10);
            for b in 0..3 {
                assert!((fit3.m[a][b] - truth3.m[a][b]).abs() < 1e-10);
            }
        }
    }

    #[test]
    fn rotation_angle_is_the_polar_turn() {
        for deg in [0.0f64, 7.5, -40.0, 135.0, 179.0] {
            let (s, c) = deg.to_radians().sin_cos();
            // A turn after an anisotropic stretch along the axes: the polar turn is the turn.
            let m2 = [[c * 1.3, -s * 0.8, 0.0], [s * 1.3, c * 0.8, 0.0], [0.0; 3]];
            let got = rotation_angle(&Affine::linear(2, m2));
            assert!((got - deg.abs()).abs() < 1e-9, "2-D {deg}: {got}");
            // 3-D: the same turn about an oblique axis, after a stretch along the axes.
            let axis = [1.0f64 / 3f64.sqrt(); 3];
            let mut r = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    let cross = match (i, j) {
                        (0, 1) => -axis[2],
                        (0, 2) => axis[1],
                        (1, 0) => axis[2],
                        (1, 2) => -axis[0],
                        (2, 0) => -axis[1],
                        (2, 1) => axis[0],
                        _ => 0.0,
                    };
                    let id = if i == j { 1.0 } else { 0.0 };
                    r[i][j] = c * id + s * cross + (1.0 - c) * axis[i] * axis[j];
                }
            }
            let stretch = [1.4, 0.9, 0.6];
            let m3 = std::array::from_fn(|i| std::array::from_fn(|j| r[i][j] * stretch[j]));
            let got = rotation_angle(&Affine::linear(3, m3));
            assert!((got - deg.abs()).abs() < 1e-6, "3-D {deg}: {got}");
        }
    }

    #[test]
    fn selection_prefers_the_smallest_turn_that_fits_nearly_as_well() {
        let turn = |deg: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            Affine::linear(2, [[c, -s, 0.0], [s, c, 0.0], [0.0; 3]])
        };
        let search = |tolerance, max_rotation| RotationSearch {
            tolerance,
            max_rotation,
            ..RotationSearch::default()
        };
        let cands = [
            (turn(100.0), 0.100),
            (turn(-12.0), 0.103),
            (turn(40.0), 0.101),
        ];
        let pick = |s: RotationSearch| rotation_angle(&select_candidate(&cands, 2, &s));
        // Within 5 % of the best: the 12° turn; within 0.1 %: the best fit.
        assert!((pick(search(0.05, None)) - 12.0).abs() < 1e-9);
        assert!((pick(search(1e-3, None)) - 100.0).abs() < 1e-9);
        // A bound leaves out the far turns, whatever their fit.
        assert!((pick(search(1e-3, Some(45.0))) - 40.0).abs() < 1e-9);
        // Nothing within the bound: the least turn.
        assert!((pick(search(1e-3, Some(5.0))) - 12.0).abs() < 1e-9);
        assert_eq!(
            select_candidate(&[], 2, &search(0.05, None)),
            Affine::identity(2)
        );
    }

    #[test]
    fn a_half_turn_that_fits_as_well_is_turned_back() {
        // An ellipse fits itself turned by 180°: a winner turned by 190° is taken back to the
        // true 10°, which fits as well and turns less.
        let oval = |n: usize, rot: f64| -> Vec<f64> {
            let pts = turned_curve(n, rot, |t| (2.0 * t.cos(), 0.8 * t.sin()));
            normalize(&pts, 2).unwrap().0
        };
        let (a, b) = (oval(60, 0.0), oval(53, 10f64.to_radians()));
        let search = RotationSearch::default();
        let pair = SearchPair {
            a: &a,
            b: &b,
            a_screen: &a,
            b_screen: &b,
            dim: 2,
            search: &search,
            keep_orientation: true,
        };
        let start = Affine::linear(2, crate::geometry::rotation_z(190f64.to_radians()));
        let flipped = pair.converge(start).1.unwrap();
        assert!((rotation_angle(&flipped.0) - 170.0).abs() < 2.0);
        let back = pair.least_turn_alike(flipped);
        assert!(
            (rotation_angle(&back) - 10.0).abs() < 2.0,
            "{}",
            rotation_angle(&back)
        );
        // Bounded below the half turn's alternatives, the winner stays.
        let bounded = RotationSearch {
            max_rotation: Some(5.0),
            ..search
        };
        let pair = SearchPair {
            search: &bounded,
            ..pair
        };
        assert_eq!(pair.least_turn_alike(flipped), flipped.0);
    }

    #[test]
    fn only_outlines_over_the_limit_are_screened_on_fewer_nodes() {
        let search = RotationSearch::default();
        let small = ellipse(SCREEN_NODE_LIMIT, 0.0);
        assert!(matches!(screen_nodes(&small, 2, &search, true), Cow::Borrowed(p) if p == small));
        let large = ellipse(185, 0.0);
        assert!(matches!(
            screen_nodes(&large, 2, &search, false),
            Cow::Borrowed(_)
        ));
        // 185 nodes: every third, 62 of them, the first kept.
        let thinned = screen_nodes(&large, 2, &search, true);
        assert_eq!(thinned.len(), 2 * 62);
        assert_eq!(&thinned[..4], &[large[0], large[1], large[6], large[7]]);
        let unlimited = RotationSearch {
            screen_node_limit: None,
            ..search
        };
        assert!(matches!(
            screen_nodes(&large, 2, &unlimited, true),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn outlines_at_or_under_the_limit_are_searched_as_without_it() {
        let unlimited = RotationSearch {
            screen_node_limit: None,
            ..RotationSearch::default()
        };
        for (n, m) in [(60, 53), (SCREEN_NODE_LIMIT, SCREEN_NODE_LIMIT - 7)] {
            let a = normalize(&ellipse(n, 0.0), 2).unwrap().0;
            let b = normalize(&ellipse(m, 2.0), 2).unwrap().0;
            let limited = robust_prealign(&a, &b, 2, &RotationSearch::default(), true);
            assert_eq!(limited, robust_prealign(&a, &b, 2, &unlimited, true));
        }
    }

    #[test]
    fn large_outlines_screened_on_fewer_nodes_find_the_turn() {
        // A three-lobed outline, whose fits at the wrong turns are local minima, with 170 and
        // 150 nodes (screened on 57 and 75).
        let lobes = |n: usize, rot: f64| -> Vec<f64> {
            let pts = turned_curve(n, rot, |t| {
                let r = 1.0 + 0.25 * (3.0 * t).cos() + 0.1 * t.sin();
                (1.3 * r * t.cos(), r * t.sin())
            });
            normalize(&pts, 2).unwrap().0
        };
        let a = lobes(170, 0.0);
        for rot in [0.3f64, 1.9, -2.6] {
            let b = lobes(150, rot);
            let search = RotationSearch::default();
            let aff = robust_prealign(&a, &b, 2, &search, true);
            let turn = aff.m[1][0].atan2(aff.m[0][0]);
            assert!((turn - rot).abs() < 0.05, "rot {rot}: {turn}");
            assert_eq!(aff, robust_prealign_serial(&a, &b, 2, &search, true));
        }
    }

    #[test]
    fn prealign_recovers_large_rotation() {
        let a = normalize(&ellipse(60, 0.0), 2).unwrap().0;
        for rot in [0.6f64, 2.0, -2.5] {
            let b = normalize(&ellipse(53, rot), 2).unwrap().0;
            let aff = robust_prealign(&a, &b, 2, &RotationSearch::default(), true);
            assert!(chamfer(&aff.apply(&a), &b, 2) < 0.06, "rot {rot}");
            // The linear part is close to the true rotation.
            assert!(
                (aff.m[0][0] - rot.cos()).abs() < 0.1 && (aff.m[1][0] - rot.sin()).abs() < 0.1,
                "rot {rot}"
            );
            // On the pool or on this thread: the same candidates in the same order, same map.
            for search in [RotationSearch::default(), RotationSearch::spec(5)] {
                let par = robust_prealign(&a, &b, 2, &search, true);
                let seq = robust_prealign_serial(&a, &b, 2, &search, true);
                assert_eq!(par, seq, "rot {rot}");
            }
        }
    }
}
