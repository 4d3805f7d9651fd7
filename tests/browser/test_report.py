#!/usr/bin/env python3
"""Opens the demo's report.html in headless Chromium and checks what a reader would see.

Usage: test_report.py PEDOMATCH_BINARY [SCREENSHOT.png]

Checks: the three plots are drawn (plotly's SVG root exists for each), no script error and no
blocked load was logged (the page's own error log and Chromium's console), moving the slider to
frame k shows frame k (label, plot title and the page's state), the plots' titles and legends lie below plotly's mode bar,
a run of part of a recording (`--frames`) opens on its first frame with objects and says which
frames were analysed, a surface run draws its 3-D view, an isocontour run shows each level of its
frame, `pedomatch match` reports are drawn (with a 3-D view for 3-D points), file names holding
markup are shown as written (plotly reads names as HTML-like text), near-identical shapes get one
cost class, the measures section draws the peak and PTI images and the stances' curves (with a
region rule and a user's point: the regions' outlines and names and the point's track),
`pedomatch register`'s register.html is drawn with its quality table, the pages make no network request
(every host resolves to nothing, and the page's Content-Security-Policy would report any load),
and `--report none` writes no report. Standard library only; needs `chromium` on PATH.
"""

import html
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def chromium(url, *extra):
    """Runs headless Chromium on `url` until the page is rendered; returns (stdout, stderr)."""
    # A profile of its own: the scenarios run two at a time.
    profile = tempfile.mkdtemp(prefix="pedomatch-chromium-")
    cmd = [
        CHROMIUM, "--headless", "--disable-gpu", "--no-sandbox", "--hide-scrollbars",
        f"--user-data-dir={profile}",
        # Nothing may be fetched: every host name resolves to nothing.
        "--host-resolver-rules=MAP * ~NOTFOUND",
        "--enable-logging=stderr", "--v=0",
        # Virtual time runs the page's timers and rendering before the DOM is dumped.
        "--virtual-time-budget=10000", *extra, url,
    ]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    return p.stdout, p.stderr


def console_errors(stderr):
    """Script errors Chromium logged from the page's console."""
    return [l for l in stderr.splitlines()
            if "CONSOLE" in l and ("Uncaught" in l or "Error" in l or "Refused" in l)]


def check_page(page, failures, name):
    """Opens a page; checks that its script finished, logged no error and reached no network.
    Returns (DOM, expect) where expect(cond, what) records a failure for this page."""
    dom, err = chromium(page, "--dump-dom")
    def expect(cond, what):
        if not cond:
            failures.append(f"{name}: {what}")
    expect('data-ready="1"' in dom, "the page's script did not finish")
    errors = re.search(r'id="js-errors">([^<]*)<', dom)
    expect(errors is not None and errors.group(1).strip() == "",
           f"the page logged errors or blocked loads: {errors.group(1) if errors else 'no log'!r}")
    expect(not console_errors(err), f"console errors: {console_errors(err)!r}")
    expect("ERR_NAME_NOT_RESOLVED" not in err, "the page tried to reach the network")
    return dom, expect


def embedded_data(report):
    """The JSON data a report embeds."""
    html = open(report, encoding="utf-8").read()
    start = html.index('id="report-data">') + len('id="report-data">')
    return json.loads(html[start:html.index("</script>", start)])


def check_frame(report, k, failures):
    dom, expect = check_page(f"file://{report}#frame={k}", failures, f"frame {k}")
    expect(len(re.findall(r'<svg class="main-svg"', dom)) >= 6,
           "the three plotly plots are not drawn (main-svg elements missing)")
    expect(f'data-frame="{k}"' in dom, "the page's state is not frame k")
    label = re.search(r'id="frame-label">([^<]*)<', dom)
    expect(label and re.match(rf"frame {k}\b", label.group(1)),
           f"the label does not say frame {k}: {label.group(1) if label else None!r}")
    titles = re.findall(r'class="g-gtitle".*?<text[^>]*>([^<]*)<', dom)
    expect(any(re.match(rf"frame {k}\b", t) for t in titles),
           f"the player's title does not say frame {k}: {titles!r}")
    check_titles_clear_of_the_mode_bar(dom, expect)
    return dom


# plotly's mode bar (its buttons, shown on hover) spans the top 2 + 22 px of a plot, at the right.
MODE_BAR_BOTTOM = 26


def check_titles_clear_of_the_mode_bar(dom, expect):
    """Every plot title's and legend's top lies below the mode bar, which would otherwise cover
    its end."""
    titles = re.findall(r'<text class="gtitle"[^>]*?\by="([0-9.]+)"[^>]*?font-size: ([0-9.]+)px[^>]*>([^<]*)<',
                        dom)
    expect(titles, "no plot title found")
    for y, size, text in titles:
        expect(float(y) - float(size) >= MODE_BAR_BOTTOM,
               f"the title {text!r} (baseline {y} px, {size} px font) is under the mode bar")
    # A legend above the plot had its last entries under the mode bar (the time series').
    for y in re.findall(r'<g class="legend"[^>]*?transform="translate\([0-9.]+,\s*([0-9.-]+)\)"', dom):
        expect(float(y) >= MODE_BAR_BOTTOM, f"a legend (top {y} px) lies under the mode bar")


def check_analysed_frames(binary, tmp, failures):
    """A run of frames 55..100 of the walk (a swing until frame 64) opens on its first frame with
    objects, states the analysed frames, and still plays the frames before them, marked."""
    walk = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                        "examples", "data", "FrasP01L.asf")
    out = os.path.join(tmp, "frames")
    subprocess.run([binary, "run", walk, "--frames", "55..100", "--out", out, "--figures", "none"],
                   check=True, stdout=subprocess.DEVNULL)
    report = os.path.join(out, "report.html")
    first = min(int(l.split(",")[1]) for l in open(os.path.join(out, "objects.csv")).readlines()[1:])
    dom, expect = check_page(f"file://{report}", failures, "--frames 55..100")
    expect(55 < first < 100, f"first frame with objects {first}")
    expect(f'data-frame="{first}"' in dom, f"the page does not open on frame {first}")
    expect("55–99 of 205 analysed" in dom, "the header does not state the analysed frames")
    dom = check_frame(report, 10, failures)
    label = re.search(r'id="frame-label">([^<]*)<', dom)
    expect(label and label.group(1).endswith("not analysed"),
           f"frame 10 is not marked as not analysed: {label.group(1) if label else None!r}")


def write_points(path, points):
    with open(path, "w") as f:
        f.write("\n".join(",".join(f"{v:.6f}" for v in p) for p in points) + "\n")


def check_markup_in_file_names(binary, tmp, failures):
    """File names holding markup are shown as written in the legend (not read as HTML by plotly);
    two identical outlines give one cost class, all costs about 0."""
    ring = [(3 * math.cos(2 * math.pi * k / 40), 2 * math.sin(2 * math.pi * k / 40))
            for k in range(40)]
    names = ['a "x" <b>.csv', "b'é.csv"]
    for n in names:
        with open(os.path.join(tmp, n), "w") as f:
            f.write("x,y\n" + "".join(f"{x:.6f},{y:.6f}\n" for x, y in ring))
    out = os.path.join(tmp, "m out")
    subprocess.run([binary, "match", *names, "--out", out, "--figures", "none"], cwd=tmp,
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    dom, expect = check_page("file://" + os.path.join(out, "report.html").replace(" ", "%20"),
                             failures, "match report (markup in names)")
    legend = [html.unescape(t) for t in re.findall(r'class="legendtext"[^>]*>([^<]*)<', dom)]
    expect(names[0] in legend and names[1] in legend,
           f"the legend does not show the file names as written: {legend!r}")
    expect("font-weight: bold" not in " ".join(re.findall(r'class="legendtext".*?</text>', dom)),
           "a legend entry is drawn in bold: its name was read as markup")
    costs = [t for t in legend if "cost" in t]
    expect(costs == ["all costs ≈ 0"], f"identical outlines: cost classes {costs!r}")


def check_measures(binary, tmp, report, failures):
    """The measures section: the demo's report draws the peak image, the PTI image and the
    stances' force curves; a run with fine regions and a user's point draws the regions'
    outlines and names and the point's track over the peak image."""
    def drawn(dom, div, until):
        start = dom.find(f'id="{div}"')
        end = dom.find(until, start + 1)
        return start >= 0 and "main-svg" in dom[start:end]
    dom, expect = check_page(f"file://{report}", failures, "measures")
    expect('<div id="measures-view">' in dom, "the measures section is hidden")
    expect(drawn(dom, "peak-regions", 'id="pti"'), "the peak image of the measures is not drawn")
    expect(drawn(dom, "pti", 'id="stance-curves"'), "the PTI image is not drawn")
    expect(drawn(dom, "stance-curves", '<p class="note"'), "the stance curves are not drawn")
    expect("pressure-time integral" in dom and "over the stance" in dom,
           "the measures' titles are missing")
    expect("PTI kPa·s" in dom, "the PTI colour bar does not name its unit")
    walk = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                        "examples", "data", "FrasP01L.asf")
    out = os.path.join(tmp, "objects")
    objects = open(os.path.join(os.path.dirname(report), "objects.csv")).read().splitlines()
    head = objects[0].split(",")
    first = dict(zip(head, objects[1].split(",")))
    points = os.path.join(tmp, "points.csv")
    with open(points, "w") as f:
        f.write(f"name,x,y,frame\nheel,{first['centroid_x']},{first['centroid_y']},{first['frame']}\n")
    subprocess.run([binary, "run", walk, "--out", out, "--figures", "none", "--region-rule", "fine",
                    "--points", points], check=True, stdout=subprocess.DEVNULL)
    dom, expect = check_page(f"file://{os.path.join(out, 'report.html')}", failures,
                             "measures with regions and points")
    legend = [html.unescape(t) for t in re.findall(r'class="legendtext"[^>]*>([^<]*)<', dom)]
    expect("regions (fine)" in legend, f"the regions' outlines are not in the legend: {legend!r}")
    expect("point heel" in legend, f"the user's point is not in the legend: {legend!r}")
    expect(">hallux<" in dom and ">mh1<" in dom, "the regions' names are not drawn")
    data = embedded_data(os.path.join(out, "report.html"))["measures"]
    expect(len(data["points"]) == 1 and len(data["points"][0]["x"]) > 1,
           "the user's point has no track in the report's data")


def check_match_reports(binary, tmp, failures):
    """`pedomatch match` of two outlines and of two 3-D point sets: each report is drawn (the
    3-D one with its WebGL scene), offline, with every match of match.json."""
    ring = lambda n, s, d: [(3 * s * math.cos(2 * math.pi * k / n) + d,  # noqa: E731
                             2 * s * math.sin(2 * math.pi * k / n)) for k in range(n)]
    write_points(os.path.join(tmp, "a.xy"), ring(40, 1.0, 0.0))
    write_points(os.path.join(tmp, "b.xy"), ring(32, 1.1, 0.4))
    bump = [(x, y, math.exp(-(x * x + y * y) / 8)) for x in range(-4, 5) for y in range(-3, 4)]
    write_points(os.path.join(tmp, "a.xyz"), bump)
    write_points(os.path.join(tmp, "b.xyz"), [(x + 0.3, y, z) for x, y, z in bump])
    for name, ext, svgs in (("outlines", "xy", 2), ("points 3-D", "xyz", 2)):
        out = os.path.join(tmp, "match-" + ext)
        subprocess.run([binary, "match", os.path.join(tmp, "a." + ext),
                        os.path.join(tmp, "b." + ext), "--out", out, "--figures", "none"],
                       check=True, stdout=subprocess.DEVNULL)
        report = os.path.join(out, "report.html")
        dom, expect = check_page(f"file://{report}", failures, f"match report ({name})")
        expect(len(re.findall(r'<svg class="main-svg"', dom)) >= svgs, "the pair is not drawn")
        legend = re.findall(r'class="legendtext"[^>]*>([^<]*)<', dom)
        summary = json.load(open(os.path.join(out, "match.json")))
        # plotly leaves empty traces out of the legend: excess only when there are some.
        expect(any(t.startswith("a.") for t in legend)
               and ("excess" in legend) == (summary["excess_matches"] > 0),
               f"the legend lacks the objects or the excess matches: {legend!r}")
        data = embedded_data(report)
        drawn = sum(sum(v is not None for v in m["x"]) for m in data["matches"] + [data["excess"]])
        expect(drawn == 2 * summary["matches"], f"{drawn // 2} of {summary['matches']} matches drawn")
        if ext == "xyz":
            expect('class="gl-container"' in dom and '<div id="surface-view">' in dom,
                   "the 3-D view is not shown")
    # Two frames of the walk: their pressure images are drawn under the outlines, with a menu.
    walk = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                        "examples", "data", "FrasP01L.asf")
    out = os.path.join(tmp, "match-frames")
    subprocess.run([binary, "match", walk, walk, "--frame", "40", "--out", out,
                    "--figures", "none"], check=True, stdout=subprocess.DEVNULL)
    dom, expect = check_page(f"file://{os.path.join(out, 'report.html')}", failures,
                             "match report (frames)")
    expect('data-images="2"' in dom, "the two pressure frames are not drawn")
    expect('class="hm"' in dom or "heatmaplayer" in dom, "no heatmap in the plot")
    expect("updatemenu" in dom, "no menu to choose the pressure image")


def check_isocontours(binary, tmp, failures):
    """An isocontour run opens on its frame and draws each level in the legend with its kPa."""
    out = os.path.join(tmp, "iso")
    subprocess.run([binary, "demo", "--out", out, "--figures", "none", "--model", "isocontour",
                    "--iso-levels", "6"], check=True, stdout=subprocess.DEVNULL)
    report = os.path.join(out, "report.html")
    data = embedded_data(report)
    frame = data["first_object_frame"]
    levels = data["overlays"]["frames"][data["shown"].index(frame)]["levels"]
    dom = check_frame(report, frame, failures)
    legend = re.findall(r'class="legendtext"[^>]*>([^<]*)<', dom)
    named = [t for t in legend if re.fullmatch(r"[0-9.]+ kPa", t)]
    if len(levels) < 3 or len(named) != len(levels):
        failures.append(f"isocontours: {len(levels)} levels, legend {legend!r}")
    # Opened without a frame, the page shows the isocontours' frame.
    dom, _ = check_page(f"file://{report}", failures, "isocontours")
    if f'data-frame="{frame}"' not in dom:
        failures.append(f"isocontours: the page does not open on frame {frame}")


def check_register_page(binary, tmp, failures):
    """`pedomatch register` of MUN104R and a copy named with markup: register.html draws its five
    images and its quality table, opens on the trial asked for, and shows the name as written."""
    src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "crates", "pedo-io",
                       "tests", "data", "MUN104R.csv")
    inputs = os.path.join(tmp, "register-in")
    os.makedirs(inputs)
    for name in ("a.csv", "<b>b.csv"):
        shutil.copy(src, os.path.join(inputs, name))
    out = os.path.join(tmp, "register")
    subprocess.run([binary, "register", inputs, "--out", out, "--template", "first"], check=True,
                   stdout=subprocess.DEVNULL)
    page = os.path.join(out, "register.html")
    dom, expect = check_page(f"file://{page}#trial=1", failures, "register.html")
    expect(len(re.findall(r'<svg class="main-svg"', dom)) >= 10,
           "the five plotly images are not drawn (main-svg elements missing)")
    expect('data-trial="1"' in dom and 'data-shown="2"' in dom,
           "the page does not show trial 1 of 2")
    quality = re.search(r'id="quality">(.*?)</table>', dom, re.S)
    expect(quality is not None and len(re.findall(r"<tr[ >]", quality.group(1))) == 3,
           "the quality table has not its header and 2 rows")
    expect("&lt;b&gt;b.csv" in dom and "<b>b.csv" not in dom,
           "the trial's name is not shown as written")


def check_surface_view(binary, tmp, failures):
    """Surfaces: the 3-D view of the pair leaving the frame shown is drawn (WebGL scene)."""
    surf = os.path.join(tmp, "surface")
    subprocess.run([binary, "demo", "--out", surf, "--figures", "none", "--model", "surface",
                    "--frames", "60..80"], check=True, stdout=subprocess.DEVNULL)
    dom = check_frame(os.path.join(surf, "report.html"), 72, failures)
    if '<div id="surface-view">' not in dom or 'class="gl-container"' not in dom:
        failures.append("surface run: the 3-D view is not shown")
    if not re.search(r'class="legendtext"[^>]*>frame 73<', dom):
        failures.append("surface run: the 3-D view does not show the pair 72 -> 73")


def check_no_report(binary, tmp, failures):
    """`--report none` writes no report.html (on a few frames: the option, not the run, is tested)."""
    none = os.path.join(tmp, "none")
    subprocess.run([binary, "demo", "--out", none, "--figures", "none", "--report", "none",
                    "--frames", "60..70"], check=True, stdout=subprocess.DEVNULL)
    if os.path.exists(os.path.join(none, "report.html")):
        failures.append("--report none wrote report.html")


def check_clamped_frame(report, failures):
    """A frame not on the slider's range is clamped to the last frame."""
    if 'data-frame="204"' not in chromium(f"file://{report}#frame=999", "--dump-dom")[0]:
        failures.append("frame 999 did not clamp to the last frame, 204")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    binary = os.path.abspath(sys.argv[1])
    screenshot = os.path.abspath(sys.argv[2]) if len(sys.argv) > 2 else None
    if CHROMIUM is None:
        sys.exit("chromium is required for the browser test (apt-get install chromium)")
    failures = []  # list.append is atomic: the scenarios' threads share it
    # The scenarios two at a time (a core each: pedomatch, then Chromium, in each); the demo's
    # own checks start once the demo is written.
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(max_workers=2) as pool:
        out = os.path.join(tmp, "demo")
        demo = pool.submit(subprocess.run, [binary, "demo", "--out", out, "--figures", "none"],
                           check=True, stdout=subprocess.DEVNULL)
        scenarios = [pool.submit(check, binary, tmp, failures) for check in (
            check_surface_view, check_isocontours, check_analysed_frames, check_match_reports,
            check_markup_in_file_names, check_register_page, check_no_report)]
        demo.result()
        report = os.path.join(out, "report.html")
        size = os.path.getsize(report)
        if size > 25 * 2**20:
            failures.append(f"report.html is {size} bytes, over 25 MB")
        scenarios += [pool.submit(check_frame, report, k, failures) for k in (0, 75, 204)]
        scenarios.append(pool.submit(check_clamped_frame, report, failures))
        scenarios.append(pool.submit(check_measures, binary, tmp, report, failures))
        if screenshot:
            chromium(f"file://{report}#frame=75", f"--screenshot={screenshot}",
                     "--window-size=1400,1300")
            if not os.path.exists(screenshot):
                failures.append("no screenshot written")
        for scenario in scenarios:
            scenario.result()  # a scenario's own error (a failed run) ends the test here
    for f in failures:
        print("FAIL:", f)
    print(f"report.html of the demo is {size / 2**20:.1f} MB")
    # Scenarios: size, frames 0 / 75 / 204 (with the titles clear of the mode bar), the clamped
    # frame, the surface view, isocontours, the analysed frames, two match reports, markup in
    # file names, --report none, the measures (demo; regions and a point), register.html.
    scenarios = 15
    failed = min(len(failures), scenarios)
    print(f"browser: {scenarios - failed} passed, {failed} failed")
    if failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
