//! Matching the nodes left over by the one-to-one search (docs/method.md §6.3 contours, §6.4 point
//! sets and meshes).

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::features::AffinityMatrix;

/// docs/method.md §6.3 on two counter-clockwise closed contours. `z` has the *smaller* contour (A,
/// `n_a` nodes) on its rows and the larger (B) on its columns; `pairs` are one-to-one `(a, b)`.
/// Every unmatched B node lying between two matched B nodes `p, q` is given an A node from the arc
/// `a(p) … a(q)`, non-decreasing along the run, so neighbours stay neighbours and no two matches
/// cross; several B nodes may share one A node. Returns the new `(a, b)` pairs with `Z ≤
/// threshold`.
pub(crate) fn contour_excess(
    z: &AffinityMatrix,
    pairs: &[(usize, usize)],
    threshold: f64,
) -> Vec<(usize, usize)> {
    let (na, nb) = (z.rows(), z.cols());
    let mut mb = vec![usize::MAX; nb];
    for &(a, b) in pairs {
        mb[b] = a;
    }
    let matched: Vec<usize> = (0..nb).filter(|&b| mb[b] != usize::MAX).collect();
    let mut out = Vec::new();
    if matched.is_empty() {
        return out;
    }
    for (idx, &p) in matched.iter().enumerate() {
        let q = matched[(idx + 1) % matched.len()];
        // Excess run p+1 … q−1 (cyclic); with a single matched node it is the whole rest.
        let len = (q + nb - p - 1) % nb;
        let len = if matched.len() == 1 { nb - 1 } else { len };
        if len == 0 {
            continue;
        }
        let run: Vec<usize> = (1..=len).map(|t| (p + t) % nb).collect();
        let (ap, aq) = (mb[p], mb[q]);
        let s = (aq + na - ap) % na;
        let (cand, monotone): (Vec<usize>, bool) = if 2 * s <= na {
            ((0..=s).map(|c| (ap + c) % na).collect(), true)
        } else {
            (vec![ap, aq], false)
        };
        let r = run.len();
        let cost = |t: usize, c: usize| z.get(cand[c], run[t]);
        let pick = if monotone {
            cheapest_monotone(r, cand.len(), cost)
        } else {
            (0..r)
                .map(|t| if cost(t, 1) < cost(t, 0) { 1 } else { 0 })
                .collect()
        };
        for t in 0..r {
            if cost(t, pick[t]) <= threshold {
                out.push((cand[pick[t]], run[t]));
            }
        }
    }
    out
}

/// docs/method.md §6.3 after an order-preserving search that may leave nodes of *both* contours
/// out (the ordered solver's gaps): `pairs` are one-to-one and keep the cyclic order. Between two
/// consecutive pairs `(u, p)` and `(v, q)` (in A's order) lie the unmatched A nodes `u+1 … v−1`
/// and B nodes `p+1 … q−1`; the cheapest monotone path from `(u, p)` to `(v, q)` that steps one
/// node along A, along B or both (dynamic time warping) gives every one of them a partner, in
/// order, so no two matches cross. Returns the path's pairs with `Z ≤ threshold`.
pub(crate) fn cell_excess(
    z: &AffinityMatrix,
    pairs: &[(usize, usize)],
    threshold: f64,
) -> Vec<(usize, usize)> {
    let (na, nb) = (z.rows(), z.cols());
    let mut anchors = pairs.to_vec();
    anchors.sort_unstable();
    let mut out = Vec::new();
    for (u, p, la, lb) in cells(&anchors, na, nb) {
        let (ra, rb) = (la + 2, lb + 2);
        // Grid index (i, j): A node u + i, B node p + j; the corners are the two pairs.
        let cost = |i: usize, j: usize| {
            let corner = (i == 0 && j == 0) || (i == ra - 1 && j == rb - 1);
            if corner {
                0.0
            } else {
                z.get((u + i) % na, (p + j) % nb)
            }
        };
        // `d`: the cheapest path to each cell; `step`: where it came from (0 diagonal, 1 along
        // A, 2 along B), the diagonal first on ties so that the path has the fewest pairs.
        let mut d = vec![f64::INFINITY; ra * rb];
        let mut step = vec![0u8; ra * rb];
        d[0] = 0.0;
        for i in 0..ra {
            for j in 0..rb {
                let from = [
                    (i > 0 && j > 0).then(|| d[(i - 1) * rb + j - 1]),
                    (i > 0).then(|| d[(i - 1) * rb + j]),
                    (j > 0).then(|| d[i * rb + j - 1]),
                ];
                // The first reachable neighbour, then only a strictly cheaper one.
                let mut best: Option<(f64, u8)> = None;
                for (k, v) in from.iter().enumerate() {
                    if let Some(v) = *v
                        && best.is_none_or(|b| v < b.0)
                    {
                        best = Some((v, k as u8));
                    }
                }
                if let Some((v, k)) = best {
                    d[i * rb + j] = v + cost(i, j);
                    step[i * rb + j] = k;
                }
            }
        }
        let (mut i, mut j) = (ra - 1, rb - 1);
        while i + j > 0 {
            (i, j) = match step[i * rb + j] {
                0 => (i - 1, j - 1),
                1 => (i - 1, j),
                _ => (i, j - 1),
            };
            if i + j > 0 && cost(i, j) <= threshold {
                out.push(((u + i) % na, (p + j) % nb));
            }
        }
    }
    out
}

/// The cells of an order-keeping match whose `pairs` are sorted by A's node: from each pair
/// `(u, p)`, the `la` A nodes and `lb` B nodes before the next pair (cyclically; with a single
/// pair, the whole rest of both contours), as `(u, p, la, lb)`. Cells with no inner node are
/// left out.
fn cells(
    pairs: &[(usize, usize)],
    na: usize,
    nb: usize,
) -> impl Iterator<Item = (usize, usize, usize, usize)> + '_ {
    pairs.iter().enumerate().filter_map(move |(idx, &(u, p))| {
        let (v, q) = pairs[(idx + 1) % pairs.len()];
        let (la, lb) = if pairs.len() == 1 {
            (na - 1, nb - 1)
        } else {
            ((v + na - u - 1) % na, (q + nb - p - 1) % nb)
        };
        (la + lb > 0).then_some((u, p, la, lb))
    })
}

/// The cheapest non-decreasing assignment of `r` run nodes to `nc` candidates in order
/// (`cost(t, c)`), by dynamic programming: `d[t][c]` is the best cost of the first `t + 1` nodes
/// with node `t` on candidate `c` and all earlier ones on candidates `≤ c`, and `best[t][c]` the
/// argmin over `c' ≤ c` of `d[t][c']`.
fn cheapest_monotone(r: usize, nc: usize, cost: impl Fn(usize, usize) -> f64) -> Vec<usize> {
    let mut d = vec![0.0; r * nc];
    let mut best = vec![0usize; r * nc];
    for t in 0..r {
        for c in 0..nc {
            let prev = if t == 0 {
                0.0
            } else {
                d[(t - 1) * nc + best[(t - 1) * nc + c]]
            };
            d[t * nc + c] = cost(t, c) + prev;
        }
        for c in 0..nc {
            let bc = if c == 0 {
                0
            } else {
                let b = best[t * nc + c - 1];
                if d[t * nc + c] < d[t * nc + b] {
                    c
                } else {
                    b
                }
            };
            best[t * nc + c] = bc;
        }
    }
    let mut pick = vec![0usize; r];
    pick[r - 1] = best[(r - 1) * nc + nc - 1];
    for t in (1..r).rev() {
        pick[t - 1] = best[(t - 1) * nc + pick[t]];
    }
    pick
}

/// docs/method.md §6.4, generalised to unordered point sets and meshes in 2-D or 3-D.
///
/// `z` has object A on its rows and B on its columns; each unmatched B node `e` (B is the larger
/// object, the one whose nodes are left over) gets an A node from the candidates formed by the
/// matches of its matched neighbours and their own neighbours in A. A candidate is admissible when
/// it keeps the angular order of those neighbours around it (no fold-over, i.e. no crossing),
/// measured in the local tangent plane; among the admissible (or, failing any, the least violating)
/// candidates the lowest `Z` wins, subject to the threshold. Nodes are processed in order of
/// decreasing number of matched neighbours, and each new match becomes usable by later ones.
///
/// `nbr_a`/`nbr_b` are neighbour lists (a mesh's 1-ring or k nearest neighbours), `pos_a`/`pos_b`
/// the aligned coordinates (row-major, `dim` per node); in 3-D each node's local normal defines
/// its tangent plane.
#[allow(clippy::too_many_arguments)]
pub(crate) fn point_set_excess(
    z: &AffinityMatrix,
    pairs: &[(usize, usize)],
    threshold: f64,
    dim: usize,
    pos_a: &[f64],
    pos_b: &[f64],
    nbr_a: &[Vec<usize>],
    nbr_b: &[Vec<usize>],
) -> Vec<(usize, usize)> {
    let nb = z.cols();
    let mut mb: Vec<Option<usize>> = vec![None; nb];
    for &(a, b) in pairs {
        mb[b] = Some(a);
    }
    let (obj_a, obj_b) = (
        Object::new(dim, pos_a, nbr_a),
        Object::new(dim, pos_b, nbr_b),
    );
    let mut out = Vec::new();
    let mut pending: Vec<usize> = (0..nb).filter(|&b| mb[b].is_none()).collect();
    while !pending.is_empty() {
        let (idx, anchors) = most_anchored(&pending, nbr_b, &mb);
        let e = pending.swap_remove(idx);
        let chosen = if anchors.is_empty() {
            // Isolated from every match: the only evidence left is Z.
            (0..z.rows())
                .min_by(|&x, &y| z.get(x, e).total_cmp(&z.get(y, e)))
                .map(|a| (a, z.get(a, e)))
        } else {
            let ring = obj_b.angular_ring(e, &anchors);
            least_folding_candidate(z, &obj_a, &obj_b, e, &ring, &mb)
        };
        if let Some((a, za)) = chosen
            && za <= threshold
        {
            out.push((a, e));
            mb[e] = Some(a);
        }
    }
    out
}

/// One object of [`point_set_excess`]: its aligned positions, neighbour lists and, in 3-D, local
/// normals (the least-variance direction of each node's neighbourhood, oriented like the global
/// least-variance axis so that both objects agree on "up"; in 2-D "up" is `z`).
struct Object<'a> {
    dim: usize,
    pos: &'a [f64],
    nbr: &'a [Vec<usize>],
    normals: Vec<[f64; 3]>,
}

impl<'a> Object<'a> {
    fn new(dim: usize, pos: &'a [f64], nbr: &'a [Vec<usize>]) -> Self {
        let normals = if dim == 3 {
            normals(pos, nbr)
        } else {
            Vec::new()
        };
        Self {
            dim,
            pos,
            nbr,
            normals,
        }
    }

    fn point(&self, i: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        p[..self.dim].copy_from_slice(&self.pos[i * self.dim..(i + 1) * self.dim]);
        p
    }

    fn normal(&self, i: usize) -> [f64; 3] {
        if self.dim == 3 {
            self.normals[i]
        } else {
            [0.0, 0.0, 1.0]
        }
    }

    /// `nodes` in angular order around node `e`, in its tangent plane.
    fn angular_ring(&self, e: usize, nodes: &[usize]) -> Vec<usize> {
        let pe = self.point(e);
        let (u, v) = tangent_basis(self.normal(e));
        let mut ring: Vec<(f64, usize)> = nodes
            .iter()
            .map(|&n| {
                let d = sub(self.point(n), pe);
                (dot(d, v).atan2(dot(d, u)), n)
            })
            .collect();
        ring.sort_by(|x, y| x.0.total_cmp(&y.0));
        ring.into_iter().map(|(_, n)| n).collect()
    }

    /// Signed area (along the normal of `at`) of the triangle `at`, `p`, `q`.
    fn turn(&self, at: usize, p: [f64; 3], q: [f64; 3]) -> f64 {
        let o = self.point(at);
        dot(cross(sub(p, o), sub(q, o)), self.normal(at))
    }
}

/// The pending B node with the most matched neighbours (the first on ties), its index in
/// `pending` and those neighbours (the ring grown to 2 when it has fewer than 2).
fn most_anchored(
    pending: &[usize],
    nbr_b: &[Vec<usize>],
    mb: &[Option<usize>],
) -> (usize, Vec<usize>) {
    let mut best = (0, Vec::new());
    for (idx, &e) in pending.iter().enumerate() {
        let nbs = matched_neighbours(e, nbr_b, mb);
        if nbs.len() > best.1.len() || idx == 0 {
            best = (idx, nbs);
        }
    }
    best
}

/// For B's node `e` with its matched neighbours `ring` (in angular order): the candidate A node
/// (the neighbours' matches and their neighbours in A) that reverses the fewest consecutive
/// neighbour pairs' orientation around it (fold-overs), the lowest `Z` on ties, with its `Z`.
fn least_folding_candidate(
    z: &AffinityMatrix,
    obj_a: &Object<'_>,
    obj_b: &Object<'_>,
    e: usize,
    ring: &[usize],
    mb: &[Option<usize>],
) -> Option<(usize, f64)> {
    let matched = |n: usize| mb[n].expect("a matched neighbour");
    let mut cand: Vec<usize> = Vec::new();
    for &n in ring {
        let a = matched(n);
        cand.push(a);
        cand.extend(obj_a.nbr[a].iter().copied());
    }
    cand.sort_unstable();
    cand.dedup();
    // Consecutive neighbour pairs around e; two neighbours make one pair, not two.
    let links = match ring.len() {
        0 | 1 => 0,
        2 => 1,
        r => r,
    };
    let mut best: Option<(usize, f64, usize)> = None; // (fold-overs, z, a)
    for &c in &cand {
        let folds = (0..links)
            .filter(|&k| {
                let (n1, n2) = (ring[k], ring[(k + 1) % ring.len()]);
                let sb = obj_b.turn(e, obj_b.point(n1), obj_b.point(n2));
                let sa = obj_a.turn(c, obj_a.point(matched(n1)), obj_a.point(matched(n2)));
                sa * sb < 0.0
            })
            .count();
        let zc = z.get(c, e);
        let better = match best {
            None => true,
            Some((bf, bz, _)) => folds < bf || (folds == bf && zc < bz),
        };
        if better {
            best = Some((folds, zc, c));
        }
    }
    best.map(|(_, zc, c)| (c, zc))
}

fn matched_neighbours(e: usize, nbr: &[Vec<usize>], mb: &[Option<usize>]) -> Vec<usize> {
    let mut nbs: Vec<usize> = nbr[e]
        .iter()
        .copied()
        .filter(|&x| mb[x].is_some())
        .collect();
    if nbs.len() < 2 {
        for &x in &nbr[e] {
            for &y in &nbr[x] {
                if y != e && mb[y].is_some() && !nbs.contains(&y) {
                    nbs.push(y);
                }
            }
        }
    }
    nbs
}

/// k nearest neighbours of every node, nearest first, the lower index first on ties (brute
/// force; objects have at most a few hundred nodes). Each node keeps its k nearest so far in
/// order while the others stream past: most are rejected by one comparison with the k-th. (A
/// selection of the k nearest among all distances, then a sort of those, took 0.2 ms per
/// 110-node surface, as long as the pair's assignment.)
pub(crate) fn knn(pos: &[f64], dim: usize, k: usize) -> Vec<Vec<usize>> {
    let n = pos.len() / dim;
    let k = k.min(n.saturating_sub(1));
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(k);
    pos.chunks_exact(dim)
        .enumerate()
        .map(|(i, p)| {
            best.clear();
            for (j, q) in pos.chunks_exact(dim).enumerate() {
                if j == i {
                    continue;
                }
                let sq = (0..dim).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>();
                // Candidates come in index order, so one that ties the k-th distance has the
                // higher index and stays out: `<` on the distance is the order (distance, index).
                if best.len() == k && best.last().is_none_or(|last| sq >= last.0) {
                    continue;
                }
                if best.len() == k {
                    best.pop();
                }
                // After every kept node at the same distance (they have lower indices).
                let at = best.partition_point(|x| x.0 <= sq);
                best.insert(at, (sq, j));
            }
            best.iter().map(|x| x.1).collect()
        })
        .collect()
}

/// 1-ring neighbours from triangles.
pub(crate) fn mesh_rings(n: usize, triangles: &[[usize; 3]]) -> Vec<Vec<usize>> {
    let mut r: Vec<Vec<usize>> = vec![Vec::new(); n];
    for t in triangles {
        for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if !r[x].contains(&y) {
                r[x].push(y);
            }
            if !r[y].contains(&x) {
                r[y].push(x);
            }
        }
    }
    r
}

fn normals(pos: &[f64], nbr: &[Vec<usize>]) -> Vec<[f64; 3]> {
    let n = pos.len() / 3;
    let p = |i: usize| [pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]];
    let global = least_variance_axis(&(0..n).collect::<Vec<_>>(), &p);
    (0..n)
        .map(|i| {
            let mut idx = nbr[i].clone();
            idx.push(i);
            let mut nv = if idx.len() >= 3 {
                least_variance_axis(&idx, &p)
            } else {
                global
            };
            if dot(nv, global) < 0.0 {
                nv = [-nv[0], -nv[1], -nv[2]];
            }
            nv
        })
        .collect()
}

fn least_variance_axis(idx: &[usize], p: &dyn Fn(usize) -> [f64; 3]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &i in idx {
        let q = p(i);
        for a in 0..3 {
            c[a] += q[a] / idx.len() as f64;
        }
    }
    let mut cov = [[0.0; 3]; 3];
    for &i in idx {
        let q = sub(p(i), c);
        for a in 0..3 {
            for b in 0..3 {
                cov[a][b] += q[a] * q[b];
            }
        }
    }
    let (vals, vecs) = super::prealign::sym_eigen3(cov);
    let k = (0..3)
        .min_by(|&x, &y| vals[x].total_cmp(&vals[y]))
        .unwrap_or(2);
    [vecs[0][k], vecs[1][k], vecs[2][k]]
}

fn tangent_basis(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = normalize(cross(helper, n));
    let v = cross(n, u);
    (u, v)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        a
    }
}

/// True if two matches cross on cyclically ordered contours: with `a`-positions and `b`-positions
/// read along both contours starting from the first pair, the order must never decrease.
/// Returns the number of order inversions of B's sequence when sorted along A (0 = no crossings),
/// treating several B nodes on one A node as ordered.
#[cfg(test)]
pub(crate) fn contour_crossings(pairs: &[(usize, usize)], na: usize, nb: usize) -> usize {
    if pairs.len() < 3 {
        return 0;
    }
    let mut p: Vec<(usize, usize)> = pairs.to_vec();
    let (a0, b0) = p[0];
    p.sort_by_key(|&(a, b)| ((a + na - a0) % na, (b + nb - b0) % nb));
    let seq: Vec<usize> = p.iter().map(|&(_, b)| (b + nb - b0) % nb).collect();
    // Cyclic sequences: count descents; a perfectly order-keeping matching has exactly one
    // wrap-around at most, which we have removed by rotating to start at the first pair.
    seq.windows(2).filter(|w| w[1] < w[0]).count()
}

/// Stage 5: the excess pairs for the one-to-one pairs `one` on `z`: along the contours when
/// `ordered`, else by the neighbourhoods of the point sets (`positions`: A's aligned coordinates
/// and B's, `dim` per node; `neighbours`: their neighbour lists, asked for only here). The
/// smaller object is always the one whose nodes are shared, unless `gaps`: the pairs come from the
/// order-preserving search, which may have left nodes of both contours out ([`cell_excess`]).
pub(crate) fn excess_pairs<'n>(
    z: &AffinityMatrix,
    one: &[(usize, usize)],
    threshold: f64,
    ordered: bool,
    gaps: bool,
    (dim, pa, pb): (usize, &[f64], &[f64]),
    neighbours: impl FnOnce() -> (&'n [Vec<usize>], &'n [Vec<usize>]),
) -> Vec<(usize, usize)> {
    let (n, m) = (z.rows(), z.cols());
    let swapped = || one.iter().map(|&(i, j)| (j, i)).collect::<Vec<_>>();
    let back = |v: Vec<(usize, usize)>| v.into_iter().map(|(j, i)| (i, j)).collect();
    if gaps {
        return cell_excess(z, one, threshold);
    }
    if ordered {
        return if n <= m {
            contour_excess(z, one, threshold)
        } else {
            back(contour_excess(&z.transposed(), &swapped(), threshold))
        };
    }
    let (na, nb) = neighbours();
    if n <= m {
        point_set_excess(z, one, threshold, dim, pa, pb, na, nb)
    } else {
        back(point_set_excess(
            &z.transposed(),
            &swapped(),
            threshold,
            dim,
            pb,
            pa,
            nb,
            na,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every node's distances sorted whole (stably, so the lower index first on ties).
    fn knn_by_full_sort(pos: &[f64], dim: usize, k: usize) -> Vec<Vec<usize>> {
        let n = pos.len() / dim;
        (0..n)
            .map(|i| {
                let mut d: Vec<(f64, usize)> = (0..n)
                    .filter(|&j| j != i)
                    .map(|j| {
                        let sq = (0..dim)
                            .map(|c| (pos[i * dim + c] - pos[j * dim + c]).powi(2))
                            .sum::<f64>();
                        (sq, j)
                    })
                    .collect();
                d.sort_by(|x, y| x.0.total_cmp(&y.0));
                d.into_iter().take(k).map(|x| x.1).collect()
            })
            .collect()
    }

    proptest::proptest! {
        /// Keeping the k nearest while the others stream past gives the full sort's lists,
        /// ties included (coordinates on a coarse grid make many equal distances).
        #[test]
        fn knn_selects_what_a_full_sort_finds(
            dim in 2usize..=3,
            k in 0usize..9,
            grid in proptest::collection::vec(0u8..4, 3..150),
        ) {
            let pos: Vec<f64> = grid.iter().map(|&g| f64::from(g)).collect();
            let pos = &pos[..pos.len() / dim * dim];
            proptest::prop_assert_eq!(knn(pos, dim, k), knn_by_full_sort(pos, dim, k));
        }
    }

    #[test]
    fn contour_excess_fills_gaps_in_order() {
        // A: 4 nodes, B: 6 nodes; one-to-one matches b0→a0, b2→a1, b3→a2, b5→a3.
        // Excess b1 (between a0,a1) and b4 (between a2,a3).
        let na = 4;
        let nb = 6;
        let mut z = vec![1.0; na * nb];
        let set = |z: &mut Vec<f64>, a: usize, b: usize, v: f64| z[a * nb + b] = v;
        for (a, b) in [(0, 0), (1, 2), (2, 3), (3, 5)] {
            set(&mut z, a, b, 0.0);
        }
        set(&mut z, 1, 1, 0.2);
        set(&mut z, 0, 1, 0.3);
        set(&mut z, 3, 4, 0.1);
        // A tempting but out-of-arc candidate for b4 must not be taken.
        set(&mut z, 0, 4, 0.0);
        let zm = AffinityMatrix::new(na, nb, z).unwrap();
        let pairs = [(0, 0), (1, 2), (2, 3), (3, 5)];
        let mut ex = contour_excess(&zm, &pairs, 1.0);
        ex.sort();
        assert_eq!(ex, vec![(1, 1), (3, 4)]);
        let mut all = pairs.to_vec();
        all.extend(&ex);
        assert_eq!(contour_crossings(&all, na, nb), 0);
        // Threshold below 0.1 drops both.
        assert!(contour_excess(&zm, &pairs, 0.05).is_empty());
    }

    #[test]
    fn contour_excess_run_is_monotone() {
        // A run of 3 excess nodes between a0 and a2: costs favour 2, 0, 1 unconstrained, but the
        // order-keeping optimum must be non-decreasing.
        let na = 6;
        let nb = 9;
        let mut z = vec![1.0; na * nb];
        let pairs = [(0usize, 0usize), (2, 4), (3, 5), (4, 6), (5, 8)];
        for &(a, b) in &pairs {
            z[a * nb + b] = 0.0;
        }
        let run = [1usize, 2, 3];
        let costs = [[0.5, 0.4, 0.1], [0.1, 0.4, 0.5], [0.5, 0.1, 0.4]]; // [t][c]
        for (t, &b) in run.iter().enumerate() {
            for c in 0..3 {
                z[c * nb + b] = costs[t][c];
            }
        }
        let zm = AffinityMatrix::new(na, nb, z).unwrap();
        let ex = contour_excess(&zm, &pairs, 1.0);
        let picks: Vec<usize> = run
            .iter()
            .map(|b| ex.iter().find(|p| p.1 == *b).unwrap().0)
            .collect();
        assert!(picks.windows(2).all(|w| w[0] <= w[1]), "{picks:?}");
        // Brute force over non-decreasing triples.
        let mut best = f64::INFINITY;
        for x in 0..3 {
            for y in x..3 {
                for w in y..3 {
                    best = best.min(costs[0][x] + costs[1][y] + costs[2][w]);
                }
            }
        }
        let got: f64 = (0..3).map(|t| costs[t][picks[t]]).sum();
        assert!((got - best).abs() < 1e-12);
    }

    /// The cheapest monotone lattice path from `(0, 0)` to `(ra − 1, rb − 1)`, by enumeration,
    /// its corners free.
    fn cheapest_path(ra: usize, rb: usize, cost: &dyn Fn(usize, usize) -> f64) -> f64 {
        fn walk(i: usize, j: usize, ra: usize, rb: usize, c: &dyn Fn(usize, usize) -> f64) -> f64 {
            if (i, j) == (ra - 1, rb - 1) {
                return 0.0;
            }
            let here = if i + j == 0 { 0.0 } else { c(i, j) };
            let mut best = f64::INFINITY;
            for (di, dj) in [(1, 1), (1, 0), (0, 1)] {
                if i + di < ra && j + dj < rb {
                    best = best.min(walk(i + di, j + dj, ra, rb, c));
                }
            }
            here + best
        }
        walk(0, 0, ra, rb, cost)
    }

    proptest::proptest! {
        /// After an order-preserving search with gaps, every node of both contours has a partner,
        /// no two matches cross, and each cell's path is the cheapest (enumeration).
        #[test]
        fn cell_excess_covers_both_contours_in_order_at_least_cost(
            (na, nb) in (2usize..7, 2usize..7),
            costs in proptest::collection::vec(0.0f64..1.0, 36),
            pick_a in proptest::collection::vec(proptest::bool::ANY, 6),
            pick_b in proptest::collection::vec(proptest::bool::ANY, 6),
            shift in 0usize..6,
        ) {
            let z = AffinityMatrix::new(na, nb, costs[..na * nb].to_vec()).unwrap();
            // k anchors: the first k picked rows onto the first k picked columns, shifted.
            let rows: Vec<usize> = (0..na).filter(|&i| pick_a[i]).collect();
            let cols: Vec<usize> = (0..nb).filter(|&j| pick_b[j]).collect();
            let k = rows.len().min(cols.len()).max(1);
            let rows: Vec<usize> = if rows.is_empty() { vec![0] } else { rows };
            let cols: Vec<usize> = if cols.is_empty() { vec![0] } else { cols };
            let one: Vec<(usize, usize)> =
                (0..k).map(|t| (rows[t], (cols[t] + shift) % nb)).collect();
            let ex = cell_excess(&z, &one, 1.0);
            let all: Vec<(usize, usize)> = one.iter().chain(&ex).copied().collect();
            for a in 0..na {
                proptest::prop_assert!(all.iter().any(|p| p.0 == a), "row {} uncovered", a);
            }
            for b in 0..nb {
                proptest::prop_assert!(all.iter().any(|p| p.1 == b), "column {} uncovered", b);
            }
            proptest::prop_assert_eq!(assign::cyclic_crossings(&all), 0);
            // Cost: each cell's cheapest path, by enumeration.
            let mut sorted = one.clone();
            sorted.sort_unstable();
            let mut want = 0.0;
            for (u, p, la, lb) in cells(&sorted, na, nb) {
                let c = |i: usize, j: usize| z.get((u + i) % na, (p + j) % nb);
                want += cheapest_path(la + 2, lb + 2, &c);
            }
            let got: f64 = ex.iter().map(|&(a, b)| z.get(a, b)).sum();
            proptest::prop_assert!((got - want).abs() < 1e-9, "{} against {}", got, want);
        }
    }
}
