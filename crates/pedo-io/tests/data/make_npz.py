"""Writes the NumPy archives of this folder with NumPy itself (np.savez / np.savez_compressed).

frames: float32 (2, 63, 27) = MUN104L.csv and half of it, NaN where the template is 0 (no sensor);
pitch_mm: a 1-D member stored first, which a reader must skip.
Run from this folder with NumPy installed: python3 make_npz.py
"""
import numpy as np

grid = np.loadtxt("MUN104L.csv", delimiter=",", dtype=np.float32)
frames = np.stack([grid, grid / 2]).astype(np.float32)
frames[:, grid == 0] = np.nan
np.savez("numpy-MUN104L-stored.npz", pitch_mm=np.array([5.0, 5.0]), frames=frames)
np.savez_compressed("numpy-MUN104L-deflated.npz", pitch_mm=np.array([5.0, 5.0]), frames=frames)
