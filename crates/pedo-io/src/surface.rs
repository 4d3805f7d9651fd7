//! Brightness surfaces (docs/method.md §8.3): the pressure of each sample as the third coordinate
//! of a triangulated surface.
//!
//! Steps: (1) noise threshold and Gaussian smoothing ([`Preprocess`]); (2) sampling of the object's
//! bounding rectangle, keeping only samples above the threshold; (3) 2-D Delaunay triangulation
//! (spade) carrying the pressure as z; (4) decimation to a target node count by greedy vertex
//! removal — the vertex whose pressure is best predicted by the least-squares plane through its
//! neighbours goes first and the hole is re-triangulated (Delaunay), so the result stays a valid
//! triangulation of a disc; convex-hull corners are kept unless [`SurfaceOptions::keep_hull`] is
//! off, so the outline survives; (5) Laplacian
//! smoothing with the semantics of `vtkSmoothPolyDataFilter` (see [`Laplacian`]); (6) z rescaled to
//! the range of x and y.

use crate::error::{IoError, Result};
use crate::grid::{CoordUnits, Grid};
use crate::preprocess::Preprocess;
use modal_core::{Shape, Topology};
use spade::handles::FixedVertexHandle;
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

/// Laplacian smoothing as `vtkSmoothPolyDataFilter` with feature-edge smoothing off: every
/// iteration moves each vertex by `relaxation × (mean of its neighbours − itself)` in x, y and z.
/// Unlike VTK, a move that would fold a triangle (bring its x-y area to a millionth of its
/// starting area or below) is taken back for that iteration, so the mesh always stays valid.
/// Interior vertices use all mesh neighbours; with `boundary_smoothing`, boundary vertices use
/// their two boundary neighbours and stay fixed where the boundary turns by more than
/// `edge_angle_deg` (corners); without it boundary vertices do not move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Laplacian {
    /// Number of smoothing passes (0: none).
    pub iterations: usize,
    /// Fraction of the way to the neighbours' mean each vertex moves per pass, in [0, 1].
    pub relaxation: f64,
    /// Smooth the boundary too (along the boundary only); off, boundary vertices stay put.
    pub boundary_smoothing: bool,
    /// Boundary vertices where the boundary turns by more than this angle (degrees) stay
    /// fixed, so corners survive.
    pub edge_angle_deg: f64,
}

impl Default for Laplacian {
    /// VTK's defaults: 20 iterations, relaxation 0.01, boundary smoothing on, edge angle 15°.
    fn default() -> Self {
        Self {
            iterations: 20,
            relaxation: 0.01,
            boundary_smoothing: true,
            edge_angle_deg: 15.0,
        }
    }
}

/// How z (pressure) is scaled at the end.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ZScale {
    /// `z' = z · max(x range, y range) / (z range)` (docs/method.md §8.3); unchanged if z is
    /// constant.
    #[default]
    MatchXY,
    /// `z' = z · factor`.
    Factor(f64),
    /// Keep pressures.
    Keep,
}

/// Options of [`surface`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceOptions {
    /// Noise threshold (before smoothing) and smoothing σ; upsampling is allowed too.
    pub preprocess: Preprocess,
    /// Samples are kept where the preprocessed value is strictly above this (default 0: contact).
    pub sample_level: f64,
    /// Sampling step in pixels of the preprocessed grid (1 = every sample).
    pub step: usize,
    /// Target node count for decimation (`None`: no decimation).
    pub max_nodes: Option<usize>,
    /// Never remove corners of the convex hull, so the outline survives decimation (the node
    /// count can then stay above `max_nodes` by at most the number of hull corners). Without it
    /// hull corners are removed like any other vertex and the outline shrinks.
    pub keep_hull: bool,
    /// Laplacian smoothing (`None`: none).
    pub laplacian: Option<Laplacian>,
    /// How z (pressure) is finally scaled against x and y.
    pub z_scale: ZScale,
    /// Units of x and y (z is in pressure units before [`ZScale`]).
    pub units: CoordUnits,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        Self {
            preprocess: Preprocess::default(),
            sample_level: 0.0,
            step: 1,
            max_nodes: None,
            keep_hull: true,
            laplacian: Some(Laplacian::default()),
            z_scale: ZScale::MatchXY,
            units: CoordUnits::Pixels,
        }
    }
}

/// A triangulated surface: points `(x, y, z)` and counter-clockwise (in x-y) triangles.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Surface {
    /// Nodes `[x, y, z]`: x = column and y = row in [`SurfaceOptions::units`], z the
    /// preprocessed pressure scaled as [`SurfaceOptions::z_scale`] says.
    pub points: Vec<[f64; 3]>,
    /// Triangles as indices into [`points`](Self::points), counter-clockwise in x-y.
    pub triangles: Vec<[usize; 3]>,
}

impl Surface {
    /// As a modal-core shape (dimension 3, `Topology::Mesh`).
    pub fn to_shape(&self) -> Result<Shape> {
        Ok(Shape::from_points_3d(
            &self.points,
            Topology::Mesh {
                triangles: self.triangles.clone(),
            },
        )?)
    }

    /// Number of distinct undirected edges.
    pub fn n_edges(&self) -> usize {
        edge_counts(&self.triangles).len()
    }

    /// V − E + F (1 for a triangulated disc).
    pub fn euler_characteristic(&self) -> i64 {
        let used = {
            let mut u = vec![false; self.points.len()];
            self.triangles.iter().flatten().for_each(|&v| u[v] = true);
            u.iter().filter(|&&b| b).count()
        };
        used as i64 - self.n_edges() as i64 + self.triangles.len() as i64
    }

    /// Signed x-y area of triangle `t` (positive = counter-clockwise).
    pub fn triangle_area_xy(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|i| self.points[i]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
    }
}

/// How many triangles share each edge `(low, high)`. Ordered, so that everything built from it
/// (the smoothing's neighbour lists, hence the order of its sums) is the same on every run.
fn edge_counts(tris: &[[usize; 3]]) -> BTreeMap<(usize, usize), usize> {
    let mut m = BTreeMap::new();
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *m.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    m
}

#[derive(Clone, Copy, Debug)]
struct Sample {
    pos: Point2<f64>,
    z: f64,
    id: usize,
}

impl HasPosition for Sample {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

type Dt = DelaunayTriangulation<Sample>;

/// Removal cost of a vertex: vertical distance to the least-squares plane through its
/// neighbours; `None` for convex-hull vertices that are corners of the hull (never removed).
fn removal_cost(tri: &Dt, h: FixedVertexHandle, keep_hull: bool) -> Option<f64> {
    let v = tri.vertex(h);
    let p = v.position();
    let z0 = v.data().z;
    let mut hull_nb = Vec::new();
    let mut nb = Vec::new();
    for e in v.out_edges() {
        let q = e.to();
        nb.push((q.position(), q.data().z));
        if e.is_part_of_convex_hull() {
            hull_nb.push(q.position());
        }
    }
    if keep_hull && !hull_nb.is_empty() {
        // On the hull: removable only between two collinear hull neighbours (exact on grid
        // coordinates), which keeps the outline.
        if hull_nb.len() != 2 {
            return None;
        }
        let (a, b) = (hull_nb[0], hull_nb[1]);
        let cross = (a.x - p.x) * (b.y - p.y) - (a.y - p.y) * (b.x - p.x);
        if cross != 0.0 {
            return None;
        }
    }
    if nb.len() < 3 {
        return None;
    }
    // Plane z = c0 + c1 (x - px) + c2 (y - py) by least squares (3x3 normal equations).
    let mut a = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for (q, z) in &nb {
        let f = [1.0, q.x - p.x, q.y - p.y];
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += f[i] * f[j];
            }
            r[i] += f[i] * z;
        }
    }
    let c0 = solve3(a, r)
        .map(|c| c[0])
        .unwrap_or_else(|| nb.iter().map(|x| x.1).sum::<f64>() / nb.len() as f64);
    Some((z0 - c0).abs())
}

/// The solution of the 3 × 3 normal equations `a x = r` (nalgebra's LU), unless `a` is singular
/// relative to `a[0][0]`, the neighbours' count.
fn solve3(a: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let a = nalgebra::Matrix3::from_fn(|i, j| a[i][j]);
    if a.determinant().abs() <= 1e-12 * a[(0, 0)].abs().max(1.0).powi(3) {
        return None;
    }
    let x = a.lu().solve(&nalgebra::Vector3::from(r))?;
    Some([x[0], x[1], x[2]])
}

/// Greedy vertex-removal decimation of a Delaunay triangulation down to `target` vertices (or,
/// with `keep_hull`, until only convex-hull corners are left).
fn decimate(tri: &mut Dt, target: usize, keep_hull: bool) {
    let n0 = tri.num_vertices();
    let mut handle_of: Vec<usize> = (0..n0).map(|i| usize::MAX - i).collect();
    for v in tri.fixed_vertices() {
        handle_of[tri.vertex(v).data().id] = v.index();
    }
    let mut version = vec![0u32; n0];
    let mut alive = vec![true; n0];
    let mut heap = BinaryHeap::new();
    let key = |c: f64| Reverse((c * 1e9).round().min(9e18) as i64);
    for v in tri.fixed_vertices() {
        if let Some(c) = removal_cost(tri, v, keep_hull) {
            heap.push((key(c), Reverse(tri.vertex(v).data().id), 0u32));
        }
    }
    while tri.num_vertices() > target.max(3) {
        let Some((_, Reverse(id), ver)) = heap.pop() else {
            break;
        };
        if !alive[id] || ver != version[id] {
            continue;
        }
        let h = FixedVertexHandle::from_index(handle_of[id]);
        let nbs: Vec<usize> = tri
            .vertex(h)
            .out_edges()
            .map(|e| e.to().data().id)
            .collect();
        tri.remove(h);
        alive[id] = false;
        // spade removes vertices by swapping the last one into the hole; refresh the one moved
        // (and fall back to a full rebuild should that ever change).
        let idx = h.index();
        if idx < tri.num_vertices() {
            let moved = tri.vertex(FixedVertexHandle::from_index(idx)).data().id;
            handle_of[moved] = idx;
        }
        let nv = tri.num_vertices();
        let stale = |j: usize, handle_of: &[usize]| {
            handle_of[j] >= nv
                || tri
                    .vertex(FixedVertexHandle::from_index(handle_of[j]))
                    .data()
                    .id
                    != j
        };
        if nbs.iter().any(|&j| alive[j] && stale(j, &handle_of)) {
            for v in tri.fixed_vertices() {
                handle_of[tri.vertex(v).data().id] = v.index();
            }
        }
        for j in nbs {
            if !alive[j] {
                continue;
            }
            version[j] += 1;
            if let Some(c) =
                removal_cost(tri, FixedVertexHandle::from_index(handle_of[j]), keep_hull)
            {
                heap.push((key(c), Reverse(j), version[j]));
            }
        }
    }
}

fn laplacian(points: &mut [[f64; 3]], tris: &[[usize; 3]], lap: &Laplacian) -> Result<()> {
    if !(lap.relaxation.is_finite() && lap.relaxation >= 0.0 && lap.relaxation <= 1.0) {
        return Err(IoError::invalid(format!(
            "relaxation must be in [0, 1], got {}",
            lap.relaxation
        )));
    }
    let n = points.len();
    let counts = edge_counts(tris);
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut bnb: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (&(a, b), &c) in &counts {
        nb[a].push(b);
        nb[b].push(a);
        if c == 1 {
            bnb[a].push(b);
            bnb[b].push(a);
        }
    }
    let cos_edge = lap.edge_angle_deg.to_radians().cos();
    // Per vertex: the neighbours it moves towards (empty = fixed).
    let mut rule: Vec<Vec<usize>> = Vec::with_capacity(n);
    for v in 0..n {
        if bnb[v].is_empty() {
            rule.push(nb[v].clone());
        } else if !lap.boundary_smoothing || bnb[v].len() != 2 {
            rule.push(Vec::new());
        } else {
            let (a, b, p) = (points[bnb[v][0]], points[bnb[v][1]], points[v]);
            let u = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
            let w = [b[0] - p[0], b[1] - p[1], b[2] - p[2]];
            let (lu, lw) = (
                u.iter().map(|x| x * x).sum::<f64>().sqrt(),
                w.iter().map(|x| x * x).sum::<f64>().sqrt(),
            );
            let cos = if lu > 0.0 && lw > 0.0 {
                (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (lu * lw)
            } else {
                1.0
            };
            rule.push(if cos < cos_edge {
                Vec::new()
            } else {
                bnb[v].clone()
            });
        }
    }
    // No triangle may fall below a millionth of its starting x-y area: a move that would fold
    // (or flatten) a triangle is taken back for that iteration, so the mesh stays valid whatever
    // the relaxation. Meshes that never come near folding are smoothed exactly as VTK does.
    let floor: Vec<f64> = tris.iter().map(|t| area_xy(points, t) * 1e-6).collect();
    let mut next = points.to_vec();
    for _ in 0..lap.iterations {
        for v in 0..n {
            let r = &rule[v];
            if r.is_empty() {
                next[v] = points[v];
                continue;
            }
            let mut m = [0.0; 3];
            for &j in r {
                for k in 0..3 {
                    m[k] += points[j][k];
                }
            }
            for k in 0..3 {
                next[v][k] = points[v][k] + lap.relaxation * (m[k] / r.len() as f64 - points[v][k]);
            }
        }
        keep_triangles_positive(points, &mut next, tris, &floor);
        points.copy_from_slice(&next);
    }
    Ok(())
}

/// Twice the signed x-y area of triangle `t` (positive = counter-clockwise).
fn area_xy(p: &[[f64; 3]], t: &[usize; 3]) -> f64 {
    let [a, b, c] = t.map(|i| p[i]);
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// Moves back to `before` the vertices of every triangle whose area in `next` is at or below its
/// floor, until none is. Terminates: each pass puts back at least one vertex, and with all of a
/// triangle's vertices back it has its previous area, which was above the floor.
fn keep_triangles_positive(
    before: &[[f64; 3]],
    next: &mut [[f64; 3]],
    tris: &[[usize; 3]],
    floor: &[f64],
) {
    loop {
        let mut moved_back = false;
        for (t, &f) in tris.iter().zip(floor) {
            if area_xy(next, t) <= f {
                for &v in t {
                    if next[v] != before[v] {
                        next[v] = before[v];
                        moved_back = true;
                    }
                }
            }
        }
        if !moved_back {
            return;
        }
    }
}

/// Builds the brightness surface of a frame (see the module documentation). An empty frame (no
/// sample above the level) or fewer than 3 non-collinear samples is an error: there is no surface.
pub fn surface(frame: &Grid, opts: &SurfaceOptions) -> Result<Surface> {
    surface_at(frame, (0, 0), opts)
}

/// Whether [`surface_of_window`] gives a frame's surface with these options: a sample level
/// at or above 0, without smoothing or upsampling (which reach past a window).
pub fn window_gives_surface(opts: &SurfaceOptions) -> bool {
    opts.sample_level >= 0.0 && opts.preprocess.is_per_sensel()
}

/// The [`surface`] of a frame that is 0 outside `window`, whose first row and column are
/// `origin` in the frame: the same surface, bit for bit, at the cost of the window, when
/// [`window_gives_surface`] (an error otherwise).
///
/// # Errors
///
/// As [`surface`]; [`IoError::InvalidInput`] when the options reach past a window.
pub fn surface_of_window(
    window: &Grid,
    origin: (usize, usize),
    opts: &SurfaceOptions,
) -> Result<Surface> {
    if !window_gives_surface(opts) {
        return Err(IoError::invalid(
            "these surface options reach past a window of the frame (smoothing, upsampling or \
             a sample level below 0)",
        ));
    }
    surface_at(window, origin, opts)
}

fn surface_at(frame: &Grid, origin: (usize, usize), opts: &SurfaceOptions) -> Result<Surface> {
    opts.units.check()?;
    if opts.step == 0 {
        return Err(IoError::invalid("sampling step must be at least 1"));
    }
    if !opts.sample_level.is_finite() {
        return Err(IoError::invalid("sample level must be finite"));
    }
    let (g, k) = opts.preprocess.apply(frame)?;
    let level = opts.sample_level;
    // Bounding rectangle of the object.
    let (mut r0, mut r1, mut c0, mut c1) = (usize::MAX, 0, usize::MAX, 0);
    for r in 0..g.rows() {
        for c in 0..g.cols() {
            if g.get(r, c) > level {
                r0 = r0.min(r);
                r1 = r1.max(r);
                c0 = c0.min(c);
                c1 = c1.max(c);
            }
        }
    }
    if r0 == usize::MAX {
        return Err(IoError::no_object(format!(
            "no sample above {level}: the frame has no object"
        )));
    }
    let mut samples = Vec::new();
    for r in (r0..=r1).step_by(opts.step) {
        for c in (c0..=c1).step_by(opts.step) {
            let z = g.get(r, c);
            if z > level {
                samples.push(Sample {
                    pos: Point2::new((c + origin.1) as f64, (r + origin.0) as f64),
                    z,
                    id: samples.len(),
                });
            }
        }
    }
    let mut tri = Dt::bulk_load_stable(samples)
        .map_err(|e| IoError::invalid(format!("triangulation failed: {e:?}")))?;
    if tri.num_inner_faces() == 0 {
        return Err(IoError::no_object(
            "fewer than 3 non-collinear samples: no surface",
        ));
    }
    if let Some(t) = opts.max_nodes {
        if t < 3 {
            return Err(IoError::invalid(format!(
                "max_nodes must be at least 3, got {t}"
            )));
        }
        decimate(&mut tri, t, opts.keep_hull);
    }
    let inv = 1.0 / k as f64;
    let mut points: Vec<[f64; 3]> = tri
        .vertices()
        .map(|v| {
            let p = opts
                .units
                .apply([v.position().x * inv, v.position().y * inv]);
            [p[0], p[1], v.data().z]
        })
        .collect();
    let mut triangles: Vec<[usize; 3]> = tri
        .inner_faces()
        .map(|f| f.vertices().map(|v| v.fix().index()))
        .collect();
    for t in triangles.iter_mut() {
        let [a, b, c] = t.map(|i| points[i]);
        if (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) < 0.0 {
            t.swap(1, 2);
        }
    }
    if let Some(lap) = &opts.laplacian {
        laplacian(&mut points, &triangles, lap)?;
        let s = Surface {
            points: points.clone(),
            triangles: triangles.clone(),
        };
        // Smoothing keeps every triangle above a fraction of its area, so this only guards
        // against a triangulation that was degenerate to begin with.
        if (0..triangles.len()).any(|t| s.triangle_area_xy(t) <= 0.0) {
            return Err(IoError::invalid(
                "degenerate triangle in the smoothed mesh: lower the relaxation or iterations",
            ));
        }
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let factor = match opts.z_scale {
        ZScale::Keep => 1.0,
        ZScale::Factor(f) if f.is_finite() => f,
        ZScale::Factor(f) => {
            return Err(IoError::invalid(format!(
                "z factor must be finite, got {f}"
            )));
        }
        ZScale::MatchXY => {
            let zr = hi[2] - lo[2];
            if zr > 0.0 {
                (hi[0] - lo[0]).max(hi[1] - lo[1]) / zr
            } else {
                1.0
            }
        }
    };
    points.iter_mut().for_each(|p| p[2] *= factor);
    Ok(Surface { points, triangles })
}
