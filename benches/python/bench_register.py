"""Footprint registration on real data: pedomatch's `register` against the registration methods
of the pedobarography literature, on the SpeedPP2D peak images (Pataky et al. 2008; 10
subjects x 60 trials of 63 x 33 sensels, from the PyPI package `jiku-data`, which is the
authors' release; installed, not vendored).

    pip install jiku-data scikit-image scipy SimpleITK
    python benches/python/bench_register.py              # tables as text
    python benches/python/bench_register.py --markdown   # tables as BENCHMARKS.md holds them
    python benches/python/bench_register.py --quick      # a few pairs per table
    python benches/python/bench_register.py --methods unregistered,pedomatch --halves tune \
        --no-study --set warp_smoothing=1e-5             # one tuning trial

Pairs (moving trial -> fixed trial, the fixed one the template): within a subject, trials
(2k, 2k+1) for k < 10; between subjects, trial k of s onto trial k of t for k < 3 and s < t.
The trials of a subject alternate between three walking speeds (the dataset's `cond`), so most
within pairs join two speeds: the "same speed" table keeps the within pairs whose two trials
share the condition (what a registration of repeated trials can reach; the other pairs differ
by the speed effect itself, which a pixel-wise test is meant to find, not a registration to
remove), and the text output gives the within pairs' rank correlation of the registered
correlation with the pair's speed difference.
Every choice of pedomatch's defaults was made on subjects 0-4 (TUNING); subjects 5-9 are
HELD OUT and reported in their own tables.

Methods on the same pairs:
  unregistered  the moving image as it is;
  principal     principal axes of the footprint masks: centroids, axis angle (the smaller turn of
                the two axis directions) and the square root of the area ratio (similarity);
  fft           phase correlation (scikit-image `phase_cross_correlation`): rotation and scale
                from the log-polar magnitude spectra, then the translation (similarity);
  min-mse       minimum-MSE alignment (scipy.optimize, Powell): rigid from the identity, then
                affine from the rigid optimum;
  bspline       SimpleITK: affine (moments-initialised, mean squares) then a B-spline
                (mesh 4 x 4, mean squares, L-BFGS-B) on top;
  pedomatch     pymodal.register(moving, template_image=fixed): whole-foot outlines, modal
                matching with the no-flip prior, thin-plate field, rigid correction, the
                non-rigid B-spline step, the final check against the unregistered overlap.
  demons        (not in the default list: an experiment) pedomatch, then SimpleITK's fast
                symmetric-forces demons (50 iterations, the field smoothed by a Gaussian of
                --demons-sd sensels): how far a dense, intensity-driven last step raises the
                fit, and the smallest Jacobian determinant of its field it needs for it.

Each table gives every metric's mean, its worst 5 % (95th percentile of MSE and XOR, 5th of
the correlation) and its worst pair; the correlation's median too (the target's statistic).
`--set KEY=VALUE` passes a pymodal.register keyword to pedomatch (how the defaults were tuned,
with `--halves tune`).

Metrics (numpy, the same for every method): mean squared pressure difference over the grid
(kPa^2); Pearson correlation over the union of the two footprints (sensels loaded above 0,
the moving one's mask carried by the method's own map, >= 0.5 after linear interpolation); mask
XOR as a percentage of the fixed footprint's sensels; time per registration (one core).
"""

import argparse
import os
import sys
import time

# One thread for every method (ITK, under SimpleITK, would otherwise use every core).
for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS",
           "ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np
from scipy import ndimage, optimize

TUNE = range(0, 5)
HELD = range(5, 10)


def load():
    try:
        import jikudata
    except ImportError:
        sys.exit("needs the PyPI package jiku-data (pip install jiku-data)")
    d = jikudata.SpeedPP2D()
    return np.asarray(d.y, dtype=float), np.asarray(d.x["cond"]), np.asarray(d.x["speed"])


def pairs_of(subjects, quick):
    within, between = [], []
    for s in subjects:
        for k in range(2 if quick else 10):
            within.append((s * 60 + 2 * k, s * 60 + 2 * k + 1))
    for s in subjects:
        for t in subjects:
            if s < t:
                for k in range(1 if quick else 3):
                    between.append((s * 60 + k, t * 60 + k))
    return within, between


# ---- maps as (2x2 matrix, offset) taking fixed (row, col) coordinates into the moving image ----


def warp(img, m, off):
    return ndimage.affine_transform(img, m, offset=off, order=1, mode="constant", cval=0.0)


def mask_of(img):
    return img > 0


def moments(mask):
    rc = np.argwhere(mask).astype(float)
    c = rc.mean(axis=0)
    cov = np.cov((rc - c).T)
    w, v = np.linalg.eigh(cov)
    major = v[:, 1]
    return c, np.arctan2(major[1], major[0]), len(rc)


def rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def principal(mov, fix):
    cm, am, nm = moments(mask_of(mov))
    cf, af, nf = moments(mask_of(fix))
    d = (am - af + np.pi / 2) % np.pi - np.pi / 2  # the smaller turn of the two axis directions
    s = np.sqrt(nm / nf)
    m = s * rot(d)
    return m, cm - m @ cf


def fft(mov, fix):
    from skimage.registration import phase_cross_correlation
    from skimage.transform import warp_polar

    shape = fix.shape
    win = np.outer(np.hanning(shape[0]), np.hanning(shape[1]))
    fm = np.abs(np.fft.fftshift(np.fft.fft2(mov * win)))
    ff = np.abs(np.fft.fftshift(np.fft.fft2(fix * win)))
    radius = min(shape) // 2
    pm = warp_polar(fm, radius=radius, scaling="log", output_shape=(360, radius))
    pf = warp_polar(ff, radius=radius, scaling="log", output_shape=(360, radius))
    sh, _, _ = phase_cross_correlation(pf[:180], pm[:180], upsample_factor=10, normalization=None)
    ang = np.deg2rad(sh[0])
    klog = radius / np.log(radius)
    scale = np.exp(sh[1] / klog)
    best = None
    # The spectrum's rotation is known up to 180 degrees: keep the turn that correlates better.
    for a in (ang, ang + np.pi):
        a = (a + np.pi) % (2 * np.pi) - np.pi
        c = (np.array(shape) - 1) / 2
        m = rot(-a) / scale
        off = c - m @ c
        turned = warp(mov, m, off)
        t, _, _ = phase_cross_correlation(fix, turned, upsample_factor=10, normalization=None)
        off2 = off - m @ t
        r = np.corrcoef(warp(mov, m, off2).ravel(), fix.ravel())[0, 1]
        if best is None or r > best[0]:
            best = (r, m, off2)
    return best[1], best[2]


def min_mse(mov, fix):
    c = (np.array(fix.shape) - 1) / 2

    def rigid(p):
        m = rot(p[0])
        return m, c - m @ c + p[1:3]

    def affine(p):
        m = np.array([[1 + p[0], p[1]], [p[2], 1 + p[3]]])
        return m, c - m @ c + p[4:6]

    def cost(p, f):
        m, off = f(p)
        return np.mean((warp(mov, m, off) - fix) ** 2)

    r = optimize.minimize(cost, np.zeros(3), args=(rigid,), method="Powell")
    m0, off0 = rigid(r.x)
    p0 = np.array([m0[0, 0] - 1, m0[0, 1], m0[1, 0], m0[1, 1] - 1, *(off0 - (c - m0 @ c))])
    a = optimize.minimize(cost, p0, args=(affine,), method="Powell")
    return affine(a.x)


def bspline(mov, fix):
    import SimpleITK as sitk

    f = sitk.GetImageFromArray(fix.astype(np.float32))
    m = sitk.GetImageFromArray(mov.astype(np.float32))
    init = sitk.CenteredTransformInitializer(
        f, m, sitk.AffineTransform(2), sitk.CenteredTransformInitializerFilter.MOMENTS
    )
    reg = sitk.ImageRegistrationMethod()
    reg.SetMetricAsMeanSquares()
    reg.SetInterpolator(sitk.sitkLinear)
    reg.SetOptimizerAsRegularStepGradientDescent(1.0, 1e-4, 200)
    reg.SetOptimizerScalesFromPhysicalShift()
    reg.SetInitialTransform(init, inPlace=False)
    aff = reg.Execute(f, m)
    bs = sitk.BSplineTransformInitializer(f, [4, 4], order=3)
    reg2 = sitk.ImageRegistrationMethod()
    reg2.SetMetricAsMeanSquares()
    reg2.SetInterpolator(sitk.sitkLinear)
    reg2.SetOptimizerAsLBFGSB(gradientConvergenceTolerance=1e-5, numberOfIterations=100)
    reg2.SetMovingInitialTransform(aff)
    reg2.SetInitialTransform(bs, inPlace=True)
    reg2.Execute(f, m)
    total = sitk.CompositeTransform([aff, bs])
    out = sitk.GetArrayFromImage(sitk.Resample(m, f, total, sitk.sitkLinear, 0.0))
    mm = sitk.GetImageFromArray(mask_of(mov).astype(np.float32))
    mk = sitk.GetArrayFromImage(sitk.Resample(mm, f, total, sitk.sitkLinear, 0.0)) >= 0.5
    return out.astype(float), mk


PEDOMATCH_KWARGS = {}
KEPT = []


def pedomatch(mov, fix):
    import pymodal

    r = pymodal.register(mov[None], template_image=fix, **PEDOMATCH_KWARGS)
    KEPT.append(r["table"][0]["map"])
    return r["peak"][0], r["mask"][0]


DEMONS_SD = [1.5]
DEMONS_JAC = []


def demons(mov, fix):
    import SimpleITK as sitk

    reg, mk = pedomatch(mov, fix)
    f = sitk.GetImageFromArray(fix.astype(np.float32))
    m = sitk.GetImageFromArray(reg.astype(np.float32))
    dem = sitk.FastSymmetricForcesDemonsRegistrationFilter()
    dem.SetNumberOfIterations(50)
    dem.SetStandardDeviations(DEMONS_SD[0])
    field = dem.Execute(f, m)
    jac = sitk.GetArrayFromImage(sitk.DisplacementFieldJacobianDeterminant(field))
    tx = sitk.DisplacementFieldTransform(sitk.Cast(field, sitk.sitkVectorFloat64))
    out = sitk.GetArrayFromImage(sitk.Resample(m, f, tx, sitk.sitkLinear, 0.0))
    mm = sitk.GetImageFromArray(mk.astype(np.float32))
    mk2 = sitk.GetArrayFromImage(sitk.Resample(mm, f, tx, sitk.sitkLinear, 0.0)) >= 0.5
    DEMONS_JAC.append(float(jac[mk2 | mask_of(fix)].min()))
    return out.astype(float), mk2


def apply_map(method, mov, fix):
    if method == "unregistered":
        return mov, mask_of(mov)
    if method == "bspline":
        return bspline(mov, fix)
    if method == "pedomatch":
        return pedomatch(mov, fix)
    if method == "demons":
        return demons(mov, fix)
    m, off = {"principal": principal, "fft": fft, "min-mse": min_mse}[method](mov, fix)
    reg = warp(mov, m, off)
    mk = warp(mask_of(mov).astype(float), m, off) >= 0.5
    return reg, mk


def metrics(reg, mk, fix):
    fm = mask_of(fix)
    mse = float(np.mean((reg - fix) ** 2))
    u = mk | fm
    corr = float(np.corrcoef(reg[u], fix[u])[0, 1])
    xor = 100.0 * float(np.count_nonzero(mk ^ fm)) / float(np.count_nonzero(fm))
    return mse, corr, xor


METHODS = ["unregistered", "principal", "fft", "min-mse", "bspline", "pedomatch"]


def run(y, pairs, methods):
    out = {}
    for meth in methods:
        rows = []
        for a, b in pairs:
            t0 = time.perf_counter()
            reg, mk = apply_map(meth, y[a], y[b])
            dt = time.perf_counter() - t0
            rows.append((*metrics(reg, mk, y[b]), dt))
        out[meth] = np.array(rows)
    return out


def spread(v, better):
    """Mean, the worst 5 % (5th or 95th percentile) and the worst value of a metric."""
    v = v[np.isfinite(v)]
    tail = np.percentile(v, 95 if better == "low" else 5)
    worst = v.max() if better == "low" else v.min()
    return np.mean(v), tail, worst


def table(title, res, markdown):
    base = res["unregistered"]
    head = ["method", "MSE (kPa²) mean / 95th pct / worst",
            "correlation median / mean / 5th pct / worst",
            "mask XOR (%) mean / 95th pct / worst",
            "pairs with XOR worse than unregistered", "ms / registration"]
    lines = []
    for meth, r in res.items():
        worse = int(np.sum(r[:, 2] > base[:, 2] + 1e-9))
        m = spread(r[:, 0], "low")
        c = spread(r[:, 1], "high")
        x = spread(r[:, 2], "low")
        lines.append([meth, f"{m[0]:.0f} / {m[1]:.0f} / {m[2]:.0f}",
                      f"{np.nanmedian(r[:, 1]):.3f} / {c[0]:.3f} / {c[1]:.3f} / {c[2]:.3f}",
                      f"{x[0]:.1f} / {x[1]:.1f} / {x[2]:.1f}", f"{worse} of {len(r)}",
                      f"{1000 * np.mean(r[:, 3]):.1f}"])
    if markdown:
        print(f"\n**{title}**\n")
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for ln in lines:
            print("| " + " | ".join(ln) + " |")
    else:
        print(f"\n{title}")
        for ln in lines:
            print("  ".join(f"{c:>24}" for c in ln))
    if "pedomatch" in res and KEPT:
        kinds = {k: KEPT.count(k) for k in sorted(set(KEPT))}
        print(f"\npedomatch's kept maps: {kinds}")
        if not markdown:
            p = res["pedomatch"]
            bad = np.nonzero(p[:, 2] > base[:, 2] + 1e-9)[0]
            for i in bad:
                print(f"  worse pair {i}: XOR {base[i, 2]:.1f} -> {p[i, 2]:.1f}")
    KEPT.clear()
    if DEMONS_JAC:
        print(f"\ndemons (sd {DEMONS_SD[0]}): the smallest Jacobian determinant of its field over the "
              f"footprints, median over the pairs {np.median(DEMONS_JAC):.2f}, smallest "
              f"{np.min(DEMONS_JAC):.2f}")
    DEMONS_JAC.clear()


def heel_peak(img):
    """The peak pressure of the footprint's heel third (the heel lies at the low rows)."""
    rows = np.nonzero(mask_of(img).any(axis=1))[0]
    return img[: rows[0] + (rows[-1] - rows[0]) // 3].max()


def speed_link(res, pairs, speed, y, cond):
    """How much of the within pairs' registered correlation the two trials' speed difference
    explains (Spearman's rank correlation, per method), and how far their heel peaks differ."""
    from scipy.stats import spearmanr

    for label, keep in (("two speeds", False), ("one speed", True)):
        r = [max(heel_peak(y[a]), heel_peak(y[b])) / min(heel_peak(y[a]), heel_peak(y[b]))
             for a, b in pairs if (cond[a] == cond[b]) == keep]
        if r:
            print(f"  pairs of {label}: {len(r)}; the higher heel peak over the lower, median "
                  f"{np.median(r):.2f}, largest {np.max(r):.2f}")
    dv = [abs(speed[a] - speed[b]) for a, b in pairs]
    for meth, r in res.items():
        print(f"  {meth}: rank correlation of |speed difference| with the correlation "
              f"{spearmanr(dv, r[:, 1])[0]:.2f}")


def study_speed(y, markdown):
    import pymodal

    t0 = time.perf_counter()
    r = pymodal.register(y, template="study")
    dt = time.perf_counter() - t0
    c = np.array([row["correlation"] for row in r["table"]])
    x = np.array([row["mask_xor_pct"] for row in r["table"]])
    msg = (f"{len(y)} peak images registered onto a study template (2 rounds, every core) in "
           f"{dt:.1f} s; median correlation with the template {np.median(c):.3f}, median mask XOR "
           f"{np.median(x):.1f} %")
    print(("\n" if markdown else "\n") + msg)


def interleaved_speed(y, n=12):
    """B-spline and pedomatch one after the other on the first n held-out between pairs: their
    time ratio under the same load, in wall-clock and in CPU time (the process's, both on one
    thread: the CPU time is what a loaded machine changes least)."""
    _, between = pairs_of(HELD, False)
    tb, tp, cb, cp = [], [], [], []
    for a, c in between[:n]:
        t0, c0 = time.perf_counter(), time.process_time()
        bspline(y[a], y[c])
        t1, c1 = time.perf_counter(), time.process_time()
        pedomatch(y[a], y[c])
        tb.append(t1 - t0)
        tp.append(time.perf_counter() - t1)
        cb.append(c1 - c0)
        cp.append(time.process_time() - c1)
    for what, b, p in (("wall-clock", tb, tp), ("CPU", cb, cp)):
        r = np.array(b) / np.array(p)
        print(f"\n{what}: B-spline median {1000 * np.median(b):.0f} ms, pedomatch median "
              f"{1000 * np.median(p):.0f} ms; ratio median {np.median(r):.1f}x, smallest "
              f"{r.min():.1f}x")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--halves", default="tune,held")
    ap.add_argument("--kinds", default="within,same,between",
                    help="within: trials (2k, 2k+1); same: those of them at one speed; between")
    ap.add_argument("--no-study", action="store_true")
    ap.add_argument("--speed", action="store_true",
                    help="only the interleaved B-spline / pedomatch timing")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a pymodal.register keyword for pedomatch (tuning), e.g. warp_spacing=8")
    ap.add_argument("--demons-sd", type=float, default=1.5,
                    help="the demons method's field smoothing (Gaussian sd, sensels)")
    args = ap.parse_args()
    DEMONS_SD[0] = args.demons_sd
    for kv in args.set:
        k, v = kv.split("=", 1)
        PEDOMATCH_KWARGS[k] = float(v) if any(ch in v for ch in ".e") else int(v)
    y, cond, speed = load()
    if args.speed:
        interleaved_speed(y)
        return
    methods = args.methods.split(",")
    for half in args.halves.split(","):
        subjects = TUNE if half == "tune" else HELD
        name = "tuning, subjects 0-4" if half == "tune" else "held out, subjects 5-9"
        within, between = pairs_of(subjects, args.quick)
        kinds = args.kinds.split(",")
        if "within" in kinds:
            res = run(y, within, methods)
            table(f"Within subjects ({name}, {len(within)} pairs)", res, args.markdown)
            if not args.markdown:
                speed_link(res, within, speed, y, cond)
        same = [(a, b) for a, b in within if cond[a] == cond[b]]
        if "same" in kinds and same:
            table(f"Within subjects, same speed ({name}, {len(same)} pairs)",
                  run(y, same, methods), args.markdown)
        if "between" in kinds:
            table(f"Between subjects ({name}, {len(between)} pairs)", run(y, between, methods),
                  args.markdown)
    if "pedomatch" in methods and not args.quick and not args.no_study:
        study_speed(y, args.markdown)


if __name__ == "__main__":
    main()
