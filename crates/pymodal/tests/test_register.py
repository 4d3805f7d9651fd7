"""pymodal.register: footprints carried onto a template's grid, checked against numpy."""

from pathlib import Path

import numpy as np
import pytest

import pymodal

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "crates" / "pedo-io" / "tests" / "data"


def mun104(side="R"):
    return np.loadtxt(DATA / f"MUN104{side}.csv", delimiter=",")


def shifted(img, dy, dx):
    out = np.zeros_like(img)
    out[dy:, dx:] = img[: img.shape[0] - dy, : img.shape[1] - dx]
    return out


def bilinear(img, x, y):
    """numpy oracle: the bilinear value of img at (column x, row y), 0 beyond the grid."""
    rows, cols = img.shape
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0

    def at(r, c):
        ok = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
        return np.where(ok, img[np.clip(r, 0, rows - 1), np.clip(c, 0, cols - 1)], 0.0)

    return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x0 + 1)) + fy * (
        (1 - fx) * at(y0 + 1, x0) + fx * at(y0 + 1, x0 + 1)
    )


def test_a_shifted_footprint_is_resampled_as_numpy_resamples_it_with_the_reported_map():
    tpl = mun104()
    trial = shifted(tpl, 2, 1)
    r = pymodal.register(trial[None], template_image=tpl)
    assert r["peak"].shape == (1,) + tpl.shape
    row = r["table"][0]
    assert row["fallback"] == 0
    assert abs(row["tx_sensels"] - 1) < 0.2 and abs(row["ty_sensels"] - 2) < 0.2
    # The map is a translation here (the outlines are the same hull moved): sampling the trial
    # at the reported affine image of every template sensel gives the registered image.
    rr, cc = np.mgrid[0 : tpl.shape[0], 0 : tpl.shape[1]].astype(float)
    x = row["m11"] * cc + row["m12"] * rr + row["tx_sensels"]
    y = row["m21"] * cc + row["m22"] * rr + row["ty_sensels"]
    oracle = bilinear(trial, x, y)
    assert np.max(np.abs(r["peak"][0] - oracle)) < 0.02 * tpl.max()
    # And it is the template again, up to the rows and columns shifted out of the grid.
    assert np.corrcoef(r["peak"][0].ravel(), tpl.ravel())[0, 1] > 0.99
    assert row["mask_xor_pct"] < 3
    assert r["mask"].dtype == bool and r["template_mask"].shape == tpl.shape


def test_a_mirrored_left_foot_goes_onto_the_right_template_without_a_flip(tmp_path):
    right = mun104("R")
    left_like = right[:, ::-1].copy()
    r = pymodal.register(np.stack([left_like, right[:, ::-1]]), template="mun104", mirror_left=True,
                         out=tmp_path / "reg")
    for row in r["table"]:
        det = row["m11"] * row["m22"] - row["m12"] * row["m21"]
        assert det > 0 and abs(row["turn_deg"]) < 10
        assert row["correlation"] > 0.99
    z = np.load(tmp_path / "reg" / "registered.npz")
    assert z["peak"].shape == (2,) + right.shape
    np.testing.assert_array_equal(z["peak"], r["peak"])
    assert list(z["trials"]) == r["trials"]
    assert (tmp_path / "reg" / "registration.csv").read_text().startswith("trial,fallback,")
    page = (tmp_path / "reg" / "register.html").read_text(encoding="utf-8")
    assert '"trials":2' in page and page.count('"mask_xor_pct"') == 2


def test_errors_are_typed():
    tpl = mun104()
    with pytest.raises(pymodal.PedomatchError, match="trial 1"):
        pymodal.register(np.stack([tpl, np.zeros_like(tpl)]), template="first")
    with pytest.raises(pymodal.OptionError):
        pymodal.register(tpl[None], max_turn=400.0)
    with pytest.raises(pymodal.InputError):
        pymodal.register(np.zeros(5))
    with pytest.raises(pymodal.PedomatchError):
        pymodal.register(tpl[None], template_image=np.zeros((4, 4)))
