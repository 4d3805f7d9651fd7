"""Writes the reconstructed format samples of this folder from the real FrasP01L.asf.

- tekscan-FrasP01L-11-20.csv: frames 11..20 of FrasP01L.asf in the layout of the Tekscan CSV
  export (every line padded with commas to the widest line, no ASCII_DATA / closing @@), as read
  by the CSV parser of the public jiwooba/HSS-TAP repository
  (additionalFiles/onfly_tekscan_2mat.m).
- footscan-FrasP01L-11-20.txt: the same frames in the layout of the RSscan/Materialise footscan
  text export as read by the public NCH-Motion-Laboratory/footscan repository (footscan.py):
  SensCountX/SensCountY grid size, LDistX/LDistY, TimeDiff, MinIdx/MaxIdx, units, FootSide,
  a [Data] peak image and [Data<k>] frames of tab-separated values, -1 outside the sensor.
  Pressures converted from kPa to N/cm2 (divided by 10).

Run from this folder: python3 reconstruct.py
"""

text = open("FrasP01L.asf", newline="").read().replace("\r\n", "\n")
header, body = text.split("ASCII_DATA @@\n", 1)
frames = {}
for block in body.split("Frame ")[1:]:
    lines = block.strip().split("\n")
    k = int(lines[0])
    frames[k] = [row.split(",") for row in lines[1:61]]
first, last = 11, 20
width = 21

def pad(line):
    return line + "," * (width - 1 - line.count(","))

out = []
for line in header.strip("\n").split("\n"):
    if line.startswith("START_FRAME"):
        line = f"START_FRAME {first}"
    if line.startswith("END_FRAME"):
        line = f"END_FRAME {last}"
    out.append(pad(line))
for k in range(first, last + 1):
    out.append(pad(""))
    out.append(pad(f"Frame {k}"))
    out.extend(",".join(r) for r in frames[k])
open("tekscan-FrasP01L-11-20.csv", "w", newline="").write("\r\n".join(out) + "\r\n")

def ncm2(v):
    return "-1" if v == "B" else f"{float(v) / 10:.1f}"

sel = [frames[k] for k in range(first, last + 1)]
peak = [[max(float(f[r][c]) for f in sel) if sel[0][r][c] != "B" else "B"
         for c in range(width)] for r in range(60)]
out = [
    "[General]",
    "UnitDistance=mm",
    "UnitPressure=N/cm2",
    "UnitTime=ms",
    "",
    "[Technical]",
    "SensCountX=60",
    f"SensCountY={width}",
    "LDistX=5.08",
    "LDistY=5.08",
    "TimeDiff=32",
    "MinIdx=1",
    f"MaxIdx={last - first + 1}",
    "FootSide=L",
    "",
    "[Data]",
]
out.extend("\t".join(ncm2(v) if v == "B" else f"{v / 10:.1f}" for v in row) for row in peak)
for i, f in enumerate(sel, start=1):
    out += ["", f"[Data{i}]"]
    out.extend("\t".join(ncm2(v) for v in row) for row in f)
open("footscan-FrasP01L-11-20.txt", "w", newline="").write("\n".join(out) + "\n")
