//! The dense correspondence field of one matched pair (docs/method.md §11): a thin-plate spline
//! fitted to the matched nodes, which carries any point of object A's plane (an interior
//! landmark, a region's pixels) to object B's, where the matches alone only carry the nodes.
//!
//! The field is the scipy `RBFInterpolator(kernel="thin_plate_spline", degree=1,
//! smoothing=λ)` of the matches, both coordinates at once: the same system, solved in
//! normalised coordinates (§11), so the same values to rounding.

// Small dense linear algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::Solve;
use faer::Mat;

use crate::error::{ModalError, OptionError, Side};
use crate::matching::MatchPair;
use crate::shape::Shape;

/// Fewest matches a field is fitted to: its affine part has three unknowns per coordinate.
const MIN_MATCHES: usize = 3;
/// Two matched nodes closer than this, relative to the matched nodes' RMS radius, are one
/// place: at λ = 0 the field would have to send one point to two places.
const COINCIDENT: f64 = 1e-9;
/// Matched nodes whose covariance, at unit RMS radius, has a determinant below this lie on one
/// line: the affine part across it is not determined (its condition would exceed ~10⁶).
const COLLINEAR: f64 = 1e-12;

/// A smooth map of the plane fitted to one pair's matches: the thin-plate spline with its affine
/// part that sends each matched node of object A to (λ = 0) or near (λ > 0) its partner in
/// object B,
///
/// ```text
/// f(x) = a₀ + A x + Σ_i w_i U(|x − x_i|),   U(r) = r² log r,
/// ```
///
/// where the `x_i` are the matched nodes of A. Among all such maps it minimises
/// `Σ_i |f(x_i) − y_i|² + λ/(8π) · J(f)`, with `J` the bending energy (the integral of the squared
/// second derivatives of each coordinate); λ = 0 interpolates the matches exactly, and an affine
/// map of the matches (`y_i = M x_i + t`, no bending) is reproduced exactly for every λ.
///
/// ```
/// use modal_core::{match_shapes, CorrespondenceField, MatchOptions, Shape, Topology};
/// let outline = |s: f64| -> Shape {
///     let p: Vec<[f64; 2]> = (0..30)
///         .map(|i| {
///             let t = i as f64 / 30.0 * std::f64::consts::TAU;
///             [s * 2.0 * t.cos(), t.sin() + 0.1 * (2.0 * t).cos()]
///         })
///         .collect();
///     Shape::from_points_2d(&p, Topology::ClosedContour).unwrap()
/// };
/// let (a, b) = (outline(1.0), outline(1.1));
/// let m = match_shapes(&a, &b, &MatchOptions::default()).unwrap();
/// let field = CorrespondenceField::fit(&a, &b, &m.pairs, 0.0).unwrap();
/// assert!(field.residuals().iter().all(|&r| r < 1e-9));
/// // The centre of A's outline goes near the centre of B's.
/// let [c] = field.apply(&[[0.0, 0.0]])[..] else { unreachable!() };
/// assert!(c[0].abs() < 0.05 && c[1].abs() < 0.05, "{c:?}");
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CorrespondenceField {
    parts: FieldParts,
    /// `parts.from` in normalised coordinates.
    centres: Vec<[f64; 2]>,
}

/// The numbers that define a [`CorrespondenceField`], for storing a field and reading it back
/// bit for bit ([`CorrespondenceField::parts`], [`CorrespondenceField::from_parts`]) without
/// solving again.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldParts {
    /// The pairs fitted, `[node of the source object, node of the target object]`: A then B for
    /// a fitted field, B then A for its inverse.
    pub pairs: Vec<[usize; 2]>,
    /// The source nodes of the pairs (the spline's centres), in the callers' units.
    pub from: Vec<[f64; 2]>,
    /// Their partners.
    pub to: Vec<[f64; 2]>,
    /// The regularisation weight λ ≥ 0.
    pub smoothing: f64,
    /// The centroid of `from`: the normalised coordinates are `(x − centre) / radius`.
    pub centre: [f64; 2],
    /// The RMS distance of `from` from `centre`.
    pub radius: f64,
    /// The spline's weight of each centre, one per output coordinate (normalised coordinates).
    pub weights: Vec<[f64; 2]>,
    /// The affine part, one row per output coordinate: `[constant, along u, along v]` of the
    /// normalised coordinates `(u, v)`.
    pub affine: [[f64; 3]; 2],
}

impl CorrespondenceField {
    /// Fits the field from object A's plane to object B's to the one-to-one `pairs` of a match
    /// (a [`MatchResult`](crate::MatchResult)'s `pairs`), with regularisation weight
    /// `smoothing` (λ ≥ 0, in the callers' units as scipy's `smoothing`).
    ///
    /// Pairs flagged `excess` are left out: the excess-node step matches one node to several
    /// (§6.3), and a map sends each point to one place, so an interpolating field cannot honour
    /// them, and a smoothing one would average them into a pull toward their middle. Pass such
    /// pairs with `excess: false` to fit them anyway. The remaining pairs must be one-to-one both
    /// ways (the field's [`inverse`](Self::inverse) is fitted to the same pairs) and their nodes
    /// must span an area on both sides.
    ///
    /// # Errors
    /// [`ModalError::FieldDimension`] unless both objects are 2-D; [`ModalError::Option`] for a
    /// smoothing that is negative or not finite; [`ModalError::MatchOutOfRange`] for a pair that
    /// names a node the object does not have; [`ModalError::TooFewMatches`] for fewer than 3
    /// one-to-one pairs; [`ModalError::CoincidentMatches`] when a node is in two pairs or two
    /// matched nodes of one object are at one place; [`ModalError::CollinearMatches`] when the
    /// matched nodes of one object lie on a line; [`ModalError::NonFiniteResult`] if the solve
    /// fails all the same.
    pub fn fit(
        a: &Shape,
        b: &Shape,
        pairs: &[MatchPair],
        smoothing: f64,
    ) -> Result<Self, ModalError> {
        for s in [a, b] {
            if s.dim() != 2 {
                return Err(ModalError::FieldDimension { dim: s.dim() });
            }
        }
        if !(smoothing.is_finite() && smoothing >= 0.0) {
            return Err(OptionError::new("smoothing", smoothing, "a finite number >= 0").into());
        }
        let mut used = Vec::with_capacity(pairs.len());
        for (k, p) in pairs.iter().enumerate().filter(|(_, p)| !p.excess) {
            for (side, node, shape) in [(Side::A, p.a, a), (Side::B, p.b, b)] {
                if node >= shape.len() {
                    let nodes = shape.len();
                    return Err(ModalError::MatchOutOfRange {
                        pair: k,
                        side,
                        node,
                        nodes,
                    });
                }
            }
            used.push([p.a, p.b]);
        }
        let point = |s: &Shape, i: usize| [s.point(i)[0], s.point(i)[1]];
        let from: Vec<[f64; 2]> = used.iter().map(|p| point(a, p[0])).collect();
        let to: Vec<[f64; 2]> = used.iter().map(|p| point(b, p[1])).collect();
        if used.len() < MIN_MATCHES {
            return Err(ModalError::TooFewMatches {
                matches: used.len(),
                min: MIN_MATCHES,
            });
        }
        // Both sides are checked now, so that the inverse of a fitted field exists too.
        let nodes_a: Vec<usize> = used.iter().map(|p| p[0]).collect();
        let nodes_b: Vec<usize> = used.iter().map(|p| p[1]).collect();
        check_spread(&from, &nodes_a, Side::A)?;
        check_spread(&to, &nodes_b, Side::B)?;
        solve(used, from, to, smoothing)
    }

    /// The images of `points` (A's coordinates) in B's coordinates. A point with a NaN or
    /// infinite coordinate maps to NaN or infinite values; far from the matches the field is
    /// its affine part plus a slowly growing bend, an extrapolation to be trusted no more than
    /// any.
    pub fn apply(&self, points: &[[f64; 2]]) -> Vec<[f64; 2]> {
        points.iter().map(|p| self.image(*p)).collect()
    }

    /// The distance from each matched node's image to its partner, in the order of
    /// [`pairs`](Self::pairs): zero to rounding at λ = 0, the price of smoothness for λ > 0.
    pub fn residuals(&self) -> Vec<f64> {
        let p = &self.parts;
        p.from
            .iter()
            .zip(&p.to)
            .map(|(x, y)| {
                let f = self.image(*x);
                (f[0] - y[0]).hypot(f[1] - y[1])
            })
            .collect()
    }

    /// The field fitted the other way, from B's plane to A's, to the same pairs and λ (its
    /// pairs read `[node of B, node of A]`).
    ///
    /// It is a fit, not the exact inverse map (the inverse of a thin-plate spline is not one):
    /// at λ = 0, `inverse.apply(field.apply(x))` is `x` to rounding at the matched nodes, and
    /// between them off by what the two fits' errors leave, which cancel to first order and grow
    /// with the bend squared. On the tests' foot outline (240 mm, 150 outline nodes matched,
    /// points inside it): bent by ±0.04 rad, as between two frames, at most 0.0075 mm; bent by
    /// ±0.4 rad, at most 0.75 mm.
    ///
    /// # Errors
    /// [`ModalError::NonFiniteResult`] if the solve fails (the pairs were checked both ways when
    /// the field was fitted).
    pub fn inverse(&self) -> Result<Self, ModalError> {
        let p = &self.parts;
        let pairs = p.pairs.iter().map(|&[a, b]| [b, a]).collect();
        solve(pairs, p.to.clone(), p.from.clone(), p.smoothing)
    }

    /// The pairs fitted, `[source node, target node]` (A, B for a fitted field; B, A for an
    /// inverse), in the order of [`residuals`](Self::residuals).
    pub fn pairs(&self) -> &[[usize; 2]] {
        &self.parts.pairs
    }

    /// The regularisation weight λ.
    pub fn smoothing(&self) -> f64 {
        self.parts.smoothing
    }

    /// The numbers that define the field.
    pub fn parts(&self) -> &FieldParts {
        &self.parts
    }

    /// A field from its [`parts`](Self::parts), as stored: checked for consistent sizes and
    /// finite values, not solved again.
    ///
    /// # Errors
    /// [`ModalError::TooFewMatches`] for fewer than 3 centres; [`ModalError::SizeMismatch`]
    /// when `to`, `pairs` or `weights` do not have one entry per centre;
    /// [`ModalError::InvalidEntry`] for a radius or smoothing that is not finite and > 0
    /// (≥ 0 for smoothing); [`ModalError::NonFiniteResult`] for a non-finite coordinate or
    /// coefficient.
    pub fn from_parts(parts: FieldParts) -> Result<Self, ModalError> {
        let n = parts.from.len();
        if n < MIN_MATCHES {
            return Err(ModalError::TooFewMatches {
                matches: n,
                min: MIN_MATCHES,
            });
        }
        for (what, found) in [
            ("field targets", parts.to.len()),
            ("field pairs", parts.pairs.len()),
            ("field weights", parts.weights.len()),
        ] {
            if found != n {
                return Err(ModalError::SizeMismatch {
                    what,
                    expected: n,
                    found,
                });
            }
        }
        let (radius, smoothing) = (parts.radius, parts.smoothing);
        if !(radius.is_finite() && radius > 0.0) {
            return Err(ModalError::InvalidEntry {
                what: "field radius",
                index: 0,
                value: radius,
            });
        }
        if !(smoothing.is_finite() && smoothing >= 0.0) {
            let value = smoothing;
            return Err(ModalError::InvalidEntry {
                what: "field smoothing",
                index: 0,
                value,
            });
        }
        let points = parts
            .from
            .iter()
            .chain(&parts.to)
            .chain(&parts.weights)
            .flatten();
        let mut numbers = points
            .chain(parts.affine.iter().flatten())
            .chain(&parts.centre);
        if !numbers.all(|v| v.is_finite()) {
            return Err(ModalError::NonFiniteResult {
                stage: "stored correspondence field",
            });
        }
        Ok(Self::new(parts))
    }

    /// The field of `parts`, its centres normalised once for every point it maps.
    fn new(parts: FieldParts) -> Self {
        let centres = parts
            .from
            .iter()
            .map(|&p| normalise(p, parts.centre, parts.radius))
            .collect();
        Self { parts, centres }
    }

    /// `f(x)`: the affine part plus the spline, in normalised coordinates (§11).
    fn image(&self, x: [f64; 2]) -> [f64; 2] {
        let p = &self.parts;
        let u = normalise(x, p.centre, p.radius);
        let mut out = [0.0; 2];
        for (c, row) in p.affine.iter().enumerate() {
            out[c] = row[0] + row[1] * u[0] + row[2] * u[1];
        }
        for (centre, w) in self.centres.iter().zip(&p.weights) {
            let k = kernel(u, *centre);
            out[0] += w[0] * k;
            out[1] += w[1] * k;
        }
        out
    }
}

/// A thin-plate smoothing spline on fixed centres, factored once: the field of the same centres
/// fitted to new values costs one back-substitution instead of a new `O(n³)` solve.
///
/// The system of [`CorrespondenceField::fit`] depends on the centres and λ only, its values on
/// the right-hand side. A registration that moves one set of points onto each frame of a
/// recording (the anchored tracks, docs/method.md §12) refits the same centres to new targets
/// every frame; [`ThinPlateBasis`] holds the spline's terms at points mapped every frame (the
/// centres themselves, tracked points), so that each frame's images are one matrix product.
///
/// ```
/// use modal_core::FactoredSpline;
/// let centres: Vec<[f64; 2]> = (0..12)
///     .map(|i| {
///         let t = i as f64 / 12.0 * std::f64::consts::TAU;
///         [3.0 * t.cos(), t.sin()]
///     })
///     .collect();
/// let spline = FactoredSpline::new(&centres, 0.0).unwrap();
/// // A shift of the values is a shift of the map, inside the outline too.
/// let shifted: Vec<[f64; 2]> = centres.iter().map(|p| [p[0] + 1.0, p[1] - 2.0]).collect();
/// let coefficients = spline.fit(&shifted).unwrap();
/// let basis = spline.basis(&[[0.5, 0.2]]);
/// let [y] = basis.apply(&coefficients)[..] else { unreachable!() };
/// assert!((y[0] - 1.5).abs() < 1e-9 && (y[1] + 1.8).abs() < 1e-9);
/// ```
#[derive(Debug, Clone)]
pub struct FactoredSpline {
    /// The centres in normalised coordinates.
    centres: Vec<[f64; 2]>,
    centre: [f64; 2],
    radius: f64,
    lu: faer::linalg::solvers::PartialPivLu<f64>,
}

/// The coefficients of a [`FactoredSpline`] fitted to one set of values: `n` weights then the
/// three affine terms, one column per output coordinate.
#[derive(Debug, Clone)]
pub struct SplineCoefficients(Mat<f64>);

/// The terms of a [`FactoredSpline`] at fixed points: `[U(|x − x_i|)…, 1, u, v]` per point, so
/// that their images under any fitted coefficients are one matrix product.
#[derive(Debug, Clone)]
pub struct ThinPlateBasis(Mat<f64>);

impl FactoredSpline {
    /// Factors the spline's system for `centres` and regularisation λ = `smoothing` (in the
    /// callers' units, as [`CorrespondenceField::fit`]).
    ///
    /// # Errors
    /// [`ModalError::Option`] for a smoothing that is negative or not finite;
    /// [`ModalError::TooFewMatches`] for fewer than 3 centres; [`ModalError::CoincidentMatches`]
    /// or [`ModalError::CollinearMatches`] (side A) when centres coincide or lie on one line.
    pub fn new(centres: &[[f64; 2]], smoothing: f64) -> Result<Self, ModalError> {
        if !(smoothing.is_finite() && smoothing >= 0.0) {
            return Err(OptionError::new("smoothing", smoothing, "a finite number >= 0").into());
        }
        let n = centres.len();
        if n < MIN_MATCHES {
            return Err(ModalError::TooFewMatches {
                matches: n,
                min: MIN_MATCHES,
            });
        }
        let nodes: Vec<usize> = (0..n).collect();
        check_spread(centres, &nodes, Side::A)?;
        let (centre, radius) = frame_of(centres);
        let u: Vec<[f64; 2]> = centres
            .iter()
            .map(|&p| normalise(p, centre, radius))
            .collect();
        let lu = system(&u, smoothing / (radius * radius)).partial_piv_lu();
        Ok(Self {
            centres: u,
            centre,
            radius,
            lu,
        })
    }

    /// The number of centres.
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// Whether there are no centres (never: [`new`](Self::new) asks for three).
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// The coefficients of the spline that sends centre `i` to (λ = 0) or near (λ > 0)
    /// `values[i]`.
    ///
    /// # Errors
    /// [`ModalError::SizeMismatch`] unless there is one value per centre;
    /// [`ModalError::NonFiniteResult`] for a value or coefficient that is not finite.
    pub fn fit(&self, values: &[[f64; 2]]) -> Result<SplineCoefficients, ModalError> {
        let n = self.centres.len();
        if values.len() != n {
            return Err(ModalError::SizeMismatch {
                what: "spline values",
                expected: n,
                found: values.len(),
            });
        }
        let rhs = Mat::<f64>::from_fn(n + 3, 2, |r, c| if r < n { values[r][c] } else { 0.0 });
        let x = self.lu.solve(&rhs);
        if !x.col_iter().all(|c| c.iter().all(|v| v.is_finite())) {
            return Err(ModalError::NonFiniteResult {
                stage: "correspondence field",
            });
        }
        Ok(SplineCoefficients(x))
    }

    /// The spline's terms at `points` (callers' units).
    pub fn basis(&self, points: &[[f64; 2]]) -> ThinPlateBasis {
        let n = self.centres.len();
        let u: Vec<[f64; 2]> = points
            .iter()
            .map(|&p| normalise(p, self.centre, self.radius))
            .collect();
        ThinPlateBasis(Mat::<f64>::from_fn(u.len(), n + 3, |r, c| {
            if c < n {
                kernel(u[r], self.centres[c])
            } else if c == n {
                1.0
            } else {
                u[r][c - n - 1]
            }
        }))
    }
}

impl ThinPlateBasis {
    /// The images of the basis's points under the spline of `coefficients` (fitted by the
    /// [`FactoredSpline`] that made this basis).
    pub fn apply(&self, coefficients: &SplineCoefficients) -> Vec<[f64; 2]> {
        let y = &self.0 * &coefficients.0;
        (0..y.nrows()).map(|r| [y[(r, 0)], y[(r, 1)]]).collect()
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.0.nrows()
    }

    /// Whether the basis holds no point.
    pub fn is_empty(&self) -> bool {
        self.0.nrows() == 0
    }
}

/// The spline's matrix for normalised centres `u` and normalised λ:
/// `[[K + λ I, P], [Pᵀ, 0]]` (§11).
fn system(u: &[[f64; 2]], lambda: f64) -> Mat<f64> {
    let n = u.len();
    let poly = |i: usize, k: usize| if k == 0 { 1.0 } else { u[i][k - 1] };
    Mat::<f64>::from_fn(n + 3, n + 3, |r, c| match (r < n, c < n) {
        (true, true) => kernel(u[r], u[c]) + if r == c { lambda } else { 0.0 },
        (true, false) => poly(r, c - n),
        (false, true) => poly(c, r - n),
        (false, false) => 0.0,
    })
}

/// `(x − centre) / radius`.
fn normalise(x: [f64; 2], centre: [f64; 2], radius: f64) -> [f64; 2] {
    [(x[0] - centre[0]) / radius, (x[1] - centre[1]) / radius]
}

/// The thin-plate kernel `U(r) = r² log r` of two points, from `r²` (no square root).
fn kernel(u: [f64; 2], v: [f64; 2]) -> f64 {
    let r2 = (u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2);
    if r2 > 0.0 {
        0.5 * r2 * r2.ln()
    } else {
        0.0
    }
}

/// Centroid and RMS radius of `points`.
fn frame_of(points: &[[f64; 2]]) -> ([f64; 2], f64) {
    let n = points.len() as f64;
    let centre = [0, 1].map(|c| points.iter().map(|p| p[c]).sum::<f64>() / n);
    let ms = points
        .iter()
        .map(|p| (p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2))
        .sum::<f64>()
        / n;
    (centre, ms.sqrt())
}

/// Checks that the matched nodes of one object (`nodes`, at `points`) are distinct places that
/// span an area, naming the object (`side`) and the nodes otherwise.
fn check_spread(points: &[[f64; 2]], nodes: &[usize], side: Side) -> Result<(), ModalError> {
    let (centre, radius) = frame_of(points);
    let coincident = |i: usize, j: usize| ModalError::CoincidentMatches {
        side,
        first: nodes[i],
        second: nodes[j],
    };
    if !(radius.is_finite() && radius > 0.0) {
        // All at one place (or beyond f64's range).
        return Err(coincident(0, 1));
    }
    let u: Vec<[f64; 2]> = points
        .iter()
        .map(|&p| normalise(p, centre, radius))
        .collect();
    // O(n²), as cheap as one row sweep of the O(n³) solve that follows.
    for i in 0..u.len() {
        for j in 0..i {
            if (u[i][0] - u[j][0]).hypot(u[i][1] - u[j][1]) < COINCIDENT {
                return Err(coincident(j, i));
            }
        }
    }
    // At unit RMS radius the covariance has trace 1; its determinant is its smaller variance
    // times the larger (≥ ½).
    let n = u.len() as f64;
    let s = |a: usize, b: usize| u.iter().map(|p| p[a] * p[b]).sum::<f64>() / n;
    if s(0, 0) * s(1, 1) - s(0, 1).powi(2) < COLLINEAR {
        return Err(ModalError::CollinearMatches { side });
    }
    Ok(())
}

/// Solves the spline's system for centres `from` and values `to` (checked by the caller):
///
/// ```text
/// [ K + λ' I   P ] [ w ]   [ to ]
/// [ Pᵀ         0 ] [ a ] = [ 0  ]
/// ```
///
/// in coordinates normalised to the centres' centroid and RMS radius `s`, with `λ' = λ / s²`:
/// the same field as scipy's system in the callers' units (§11), with entries of order one
/// whatever the units. LU with partial pivoting, as scipy's LAPACK `gesv`.
fn solve(
    pairs: Vec<[usize; 2]>,
    from: Vec<[f64; 2]>,
    to: Vec<[f64; 2]>,
    smoothing: f64,
) -> Result<CorrespondenceField, ModalError> {
    let n = from.len();
    let (centre, radius) = frame_of(&from);
    let u: Vec<[f64; 2]> = from.iter().map(|&p| normalise(p, centre, radius)).collect();
    let lhs = system(&u, smoothing / (radius * radius));
    let rhs = Mat::<f64>::from_fn(n + 3, 2, |r, c| if r < n { to[r][c] } else { 0.0 });
    let x = lhs.partial_piv_lu().solve(&rhs);
    let weights: Vec<[f64; 2]> = (0..n).map(|i| [x[(i, 0)], x[(i, 1)]]).collect();
    let affine = [0, 1].map(|c| [x[(n, c)], x[(n + 1, c)], x[(n + 2, c)]]);
    if !weights
        .iter()
        .flatten()
        .chain(affine.iter().flatten())
        .all(|v| v.is_finite())
    {
        return Err(ModalError::NonFiniteResult {
            stage: "correspondence field",
        });
    }
    Ok(CorrespondenceField::new(FieldParts {
        pairs,
        from,
        to,
        smoothing,
        centre,
        radius,
        weights,
        affine,
    }))
}
