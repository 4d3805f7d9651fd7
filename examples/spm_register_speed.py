"""Pixel-wise statistics on registered footprints: slow against fast walking, SpeedPP2D.

The SpeedPP2D peak-pressure images (Pataky et al. 2008: 10 subjects, 60 trials each at slow,
normal and fast walking, 63 x 33 sensels; the PyPI package ``jiku-data``, the authors' release)
are registered onto one study template with ``pymodal.register``. Each subject's registered
slow trials and fast trials are averaged, and the two conditions compared sensel by sensel with
spm1d's non-parametric paired t-test (permutations of the conditions within subjects; the
threshold t* from the distribution of the largest t over the whole image, so it holds for every
sensel at once, as in Pataky et al. 2008).

    pip install jiku-data 'pedomatch[spm]'      # spm1d; matplotlib for --figure
    python examples/spm_register_speed.py [--trials 8] [--iterations 1000] [--figure out.png]

Without jiku-data or spm1d the script says which is missing and exits 0, so that it runs
anywhere (``make examples``).
"""

import argparse
import sys
from collections import Counter

import numpy as np

SLOW, FAST = 1, 3  # SpeedPP2D's condition codes (1 slow, 2 normal, 3 fast)


def load(trials):
    """Peak images, subject and condition of the first `trials` slow and fast trials of each
    subject."""
    import jikudata

    d = jikudata.SpeedPP2D()
    y = np.asarray(d.y, dtype=float)
    subj, cond = np.asarray(d.x["subj"]), np.asarray(d.x["cond"])
    keep = []
    for s in np.unique(subj):
        for c in (SLOW, FAST):
            keep.extend(np.flatnonzero((subj == s) & (cond == c))[:trials])
    keep = np.array(keep)
    return y[keep], subj[keep], cond[keep]


def subject_means(stack, subj, cond):
    """One mean registered image per subject and condition: (subjects, rows, cols) twice."""
    subjects = np.unique(subj)
    mean = lambda c: np.array([stack[(subj == s) & (cond == c)].mean(axis=0) for s in subjects])
    return mean(SLOW), mean(FAST)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=8, help="trials per subject and condition")
    ap.add_argument("--iterations", type=int, default=1000, help="permutations (at most 2^10)")
    ap.add_argument("--figure", help="write the mean images and the t map to this PNG")
    args = ap.parse_args()
    try:
        import jikudata  # noqa: F401
    except ImportError:
        print("jiku-data is not installed (pip install jiku-data): nothing to register")
        return 0
    try:
        import spm1d
    except ImportError:
        print("spm1d is not installed (pip install 'pedomatch[spm]'): no test run")
        return 0
    import pymodal

    y, subj, cond = load(args.trials)
    r = pymodal.register(y, template="study")
    stack = r["peak"]  # every trial on the template's grid, (trials, rows, cols)
    maps = Counter(row["map"] for row in r["table"])
    print(f"{len(y)} trials registered onto a study template {stack.shape[1:]}: "
          f"median correlation {np.median([row['correlation'] for row in r['table']]):.3f}, "
          f"maps kept {dict(maps)}")

    slow, fast = subject_means(stack, subj, cond)
    foot = (slow > 0).all(axis=0) | (fast > 0).all(axis=0)  # sensels loaded in every subject
    # spm1d's tests take one row per observation: the image's sensels as one flat field. The
    # non-parametric threshold is of the largest t over the field, whatever its shape.
    snpm = spm1d.stats.nonparam.ttest_paired(fast[:, foot], slow[:, foot])
    inference = snpm.inference(alpha=0.05, two_tailed=True, iterations=args.iterations)
    t = np.full(foot.shape, np.nan)
    t[foot] = inference.z
    above = np.abs(inference.z) > inference.zstar
    print(f"paired non-parametric t-test, fast vs slow, {len(slow)} subjects, {foot.sum()} sensels:")
    print(f"  t* = {inference.zstar:.2f} (alpha 0.05, two-tailed, {args.iterations} permutations)")
    print(f"  sensels above t*: {int((inference.z > inference.zstar).sum())} higher when fast, "
          f"{int((inference.z < -inference.zstar).sum())} lower; {int(above.sum())} in all")
    if args.figure:
        figure(args.figure, slow.mean(axis=0), fast.mean(axis=0), t, inference.zstar)
    return 0


def figure(path, slow, fast, t, zstar):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(7, 4))
    for a, img, title in zip(ax, (slow, fast), ("slow (kPa)", "fast (kPa)")):
        fig.colorbar(a.imshow(img, cmap="jet"), ax=a, shrink=0.7)
        a.set_title(title)
    lim = np.nanmax(np.abs(t))
    fig.colorbar(ax[2].imshow(t, cmap="RdBu_r", vmin=-lim, vmax=lim), ax=ax[2], shrink=0.7)
    ax[2].contour(np.abs(np.nan_to_num(t)) > zstar, levels=[0.5], colors="k", linewidths=0.8)
    ax[2].set_title(f"t, |t| > {zstar:.2f} outlined")
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"  figure: {path}")


if __name__ == "__main__":
    sys.exit(main())
