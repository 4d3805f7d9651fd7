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
- zebris-FrasP01L-26-55.xml: frames 26..55 (swing, heel strike, roll-over, toe-off, swing) in
  the layout of the Zebris FDM raw-data XML export as read by the public HPI-CH/TRIPOD
  repository (src/preprocessing/convert_zebris.py): the plate's <cell_count>, a pressure <clip>
  with <cell_size>, <frequency>, <units>, <count>, <begin> and one <quant> per frame holding the
  window of loaded sensors (<cell_begin>, <cell_count>, <cells> x fastest, y pointing forwards),
  <quant/> for an unloaded frame, and a treadmill-velocity <clip>. The F-Scan image is placed on
  a 30 x 80 plate with its top-left sensel at x = 5 and 10 rows below the plate's far end;
  <cell_size> is the F-Scan's 5.08 mm, <frequency> its 31.25 Hz; N/cm2.
- zebris-FrasP01L-26-55.json.gz: the same frames in the gzip-compressed JSON form that
  convert_zebris.py writes (cell_count, cell_size, frequency, pressure_unit, sample_count,
  begin, samples with origin, size, pressure, velocity).

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

# Zebris raw-data export (XML) and TRIPOD's JSON form of it.
import gzip, json

zf, zl = 26, 55
PLATE_X, PLATE_Y, OX, OY = 30, 80, 5, 10
samples = []
for k in range(zf, zl + 1):
    f = frames[k]
    loaded = {}
    for r in range(60):
        for c in range(width):
            v = 0.0 if f[r][c] == "B" else float(f[r][c]) / 10
            if v > 0:
                loaded[(OX + c, PLATE_Y - 1 - (OY + r))] = v
    if not loaded:
        samples.append(None)
        continue
    xs = [x for x, _ in loaded]
    ys = [y for _, y in loaded]
    x0, y0 = min(xs), min(ys)
    w, h = max(xs) - x0 + 1, max(ys) - y0 + 1
    cells = [loaded.get((x0 + i, y0 + j), 0.0) for j in range(h) for i in range(w)]
    samples.append(((x0, y0), (w, h), [round(v, 1) for v in cells]))

velocity = [round(1.10 + 0.01 * (i % 3), 2) for i in range(len(samples))]
out = ['<?xml version="1.0" encoding="UTF-8"?>', "<measurement>",
       f"  <cell_count><x>{PLATE_X}</x><y>{PLATE_Y}</y></cell_count>",
       "  <movements>", "    <movement>", "      <clips>", "        <clip>",
       "          <cell_size><x>5.08</x><y>5.08</y></cell_size>",
       "          <frequency>31.25</frequency>", "          <units>N/cm2</units>",
       f"          <count>{len(samples)}</count>", "          <begin>0.832</begin>",
       "          <data>"]
for s_ in samples:
    if s_ is None:
        out.append("            <quant/>")
        continue
    (x0, y0), (w, h), cells = s_
    out += ["            <quant>",
            f"              <cell_begin><x>{x0}</x><y>{y0}</y></cell_begin>",
            f"              <cell_count><x>{w}</x><y>{h}</y></cell_count>",
            "              <cells>" + " ".join(f"{v:.1f}" for v in cells) + "</cells>",
            "            </quant>"]
out += ["          </data>", "        </clip>", "        <clip>",
        "          <units>km/h</units>", f"          <count>{len(samples)}</count>",
        "          <begin>0.832</begin>", "          <data>"]
out += [f"            <quant>{v}</quant>" for v in velocity]
out += ["          </data>", "        </clip>", "      </clips>", "    </movement>",
        "  </movements>", "</measurement>"]
open(f"zebris-FrasP01L-{zf}-{zl}.xml", "w", newline="").write("\r\n".join(out) + "\r\n")

tripod = {
    "cell_count": {"x": PLATE_X, "y": PLATE_Y},
    "cell_size": {"x": 5.08, "y": 5.08},
    "frequency": 31.25,
    "pressure_unit": "N/cm2",
    "time_unit": "s",
    "velocity_unit": "km/h",
    "sample_count": len(samples),
    "begin": 0.832,
    "samples": [
        {"origin": {"x": None, "y": None}, "size": {"x": 0, "y": 0}, "pressure": [],
         "velocity": v}
        if s_ is None else
        {"origin": {"x": s_[0][0], "y": s_[0][1]}, "size": {"x": s_[1][0], "y": s_[1][1]},
         "pressure": s_[2], "velocity": v}
        for s_, v in zip(samples, velocity)
    ],
}
with gzip.GzipFile(f"zebris-FrasP01L-{zf}-{zl}.json.gz", "wb", mtime=0) as g:
    g.write(json.dumps(tripod, indent=4).encode("ascii"))
