#!/usr/bin/env python3
"""Writes docs/RESULTS.md from what scripts/results.sh measured: the scored PLYs and JSON
summaries of `upd analyze` and `upd baseline`, and the folder of `upd evaluate`. Every number in
the report is computed here from those files; the prose around them is fixed. Standard library
only (python3 on a clean Debian 12).

  results_report.py --work DIR --figures REL --out DIR --eval STATUS --quick 0|1 --data DIR
  results_report.py --has-colour FILE.ply        exit 0 when the PLY has red/green/blue
"""
import argparse
import json
import math
import os
import re
import struct
import sys

PLY_TYPES = {"float": "f", "float32": "f", "uchar": "B", "uint8": "B", "double": "d",
             "int": "i", "uint": "I"}
SQRT1_2 = math.sqrt(0.5)


def ply_header(path):
    with open(path, "rb") as f:
        props, n, origin = [], 0, (0.0, 0.0, 0.0)
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            w = line.split()
            if w[:2] == ["element", "vertex"]:
                n = int(w[2])
            elif w[:1] == ["property"]:
                props.append((w[1], w[2]))
            elif w[:2] == ["comment", "sensor_origin"]:
                origin = tuple(float(v) for v in w[2:5])
            elif line == "end_header":
                return props, n, origin, f.tell()


def read_ply(path, names):
    """The columns `names` of a binary little-endian PLY, as lists."""
    props, n, _, offset = ply_header(path)
    fmt = "<" + "".join(PLY_TYPES[t] for t, _ in props)
    index = {name: k for k, (_, name) in enumerate(props)}
    with open(path, "rb") as f:
        f.seek(offset)
        rows = list(struct.iter_unpack(fmt, f.read(n * struct.calcsize(fmt))))
    return {name: [r[index[name]] for r in rows] for name in names}


def finite(values):
    return [v for v in values if v == v and abs(v) != float("inf")]


def pct(part, whole):
    return 100.0 * part / whole if whole else float("nan")


def quantile(sorted_values, q):
    return sorted_values[int(q * (len(sorted_values) - 1))] if sorted_values else float("nan")


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |" for r in rows]
    return "\n".join(out)


def f1(v):
    return "-" if v != v else "%.1f" % v


def image(fig, name, alt):
    return "![%s](%s/%s)" % (alt, fig, name)


# ---------------------------------------------------------------------------- the corner

ZETA_BANDS = [("< 0.707", -1, SQRT1_2), ("[0.707, 0.75)", SQRT1_2, 0.75), ("[0.75, 0.85]", 0.75, 0.85 + 1e-9),
              ("(0.85, 0.95)", 0.85 + 1e-9, 0.95), (">= 0.95", 0.95, 2)]


def corner_row(label, zeta):
    z = sorted(finite(zeta))
    bands = [f1(pct(sum(1 for v in z if lo <= v < hi), len(z))) for _, lo, hi in ZETA_BANDS]
    in_70_75 = f1(pct(sum(1 for v in z if 0.70 <= v < 0.75), len(z)))
    return [label, len(z), "%.3f" % z[0], "%.3f" % quantile(z, 0.5)] + bands + [in_70_75]


def strip_origin_copy(src, dst):
    """The PLY without its `comment sensor_origin` line: a cloud whose viewpoint was lost."""
    with open(src, "rb") as f:
        data = f.read()
    with open(dst, "wb") as f:
        f.write(re.sub(rb"comment sensor_origin [^\n]*\n", b"", data, count=1))


def corner_section(work, fig, quick):
    rows = []
    for d in ["0.1", "0.3", "0.5", "1.0"]:
        rows.append(corner_row("%s m" % d, read_ply(os.path.join(work, "corner-%s.ply" % d), ["scalar_zeta"])["scalar_zeta"]))
    ideal = read_ply(os.path.join(work, "corner-ideal-1.0.ply"), ["scalar_zeta"])["scalar_zeta"]
    rows.append(corner_row("1.0 m, 4-neighbour normals", ideal))
    extra = []
    for d in ["0.1", "1.0"]:
        p = os.path.join(work, "corner-noorigin-%s.ply" % d)
        if os.path.exists(p):
            extra.append(corner_row("%s m, origin (0, 0, 0)" % d, read_ply(p, ["scalar_zeta"])["scalar_zeta"]))
    wall = read_ply(os.path.join(work, "corner-1.0.ply"), ["x", "z", "nx"])
    wall_n = [nx for x, z, nx in zip(wall["x"], wall["z"], wall["nx"]) if x == 0 and z > 0]
    out_n = sum(1 for nx in wall_n if nx > 0)
    head = ["d_m", "points", "min zeta", "median"] + ["zeta " + b[0] + " [%]" for b in ZETA_BANDS] + ["[0.70, 0.75) [%]"]
    ideal_share = corner_row("", ideal)[-1]
    share_1 = rows[3][-1]
    paper_band_1 = rows[3][6]
    spacing = "2 cm (--quick)" if quick else "1 cm"
    return f"""## Case study 1: the 90 deg corner

The paper's corner: a floor and a wall, each 1 x 1 m, sampled every {spacing} (`upd scene
corner`), scored on every point without pre-processing by the exact path (`[UpdParams] method =
exact`, PCA normals over 0.1 m). Up is +z; the sensor origin (1.5, 0.5, 1) travels in the
scene's PLY (`comment sensor_origin`), and the normals of the wall, turned towards it, all point
out of the wall: {out_n} of {len(wall_n)} wall points have n_x > 0.

{image(fig, "corner-zeta-0.1.png", "corner, d_m = 0.1 m")}
{image(fig, "corner-zeta-0.5.png", "corner, d_m = 0.5 m")}
{image(fig, "corner-zeta-1.0.png", "corner, d_m = 1.0 m")}

At d_m = 0.1 m only a band 0.1 m wide on each side of the edge departs from green; at 0.5 m the
band covers half of each plane; at 1.0 m every point's ball reaches the other plane and the
whole corner is blue, darkest along the edge's middle where the two planes are balanced.

{image(fig, "corner-normals-0.1.png", "corner, label and normals")}

{image(fig, "corner-histogram.png", "corner histogram at d_m 0.3 and 1.0 m")}

{table(head, rows + extra)}

**Against the paper's text.** The paper states that at the large d_m more than 80 % of the
corner's zeta lie in [0.75, 0.85]. We measure {paper_band_1} % there at d_m = 1.0 m and
{share_1} % in [0.70, 0.75) ({ideal_share} % with normals from the 4-neighbourhood, which keep
both planes exact up to the edge). The difference is geometry, not noise: with exact normals a
point whose ball holds a share f of floor points and 1 - f of wall points has zeta =
sqrt(f^2 + (1 - f)^2), so zeta in [0.75, 0.85] needs the minority plane to hold 17-32 % of the
ball, and zeta < 0.75 any share above 32 %. On a 1 x 1 m corner a 1 m ball reaches well into both
planes from almost every point, so most shares are near one half and zeta near sqrt(2)/2 = 0.707.
The paper's bins would fit a smaller d_m relative to the corner (at d_m = 0.5 m we measure
{rows[2][6]} % in [0.75, 0.85]) or a larger corner. The minimum stays above sqrt(2)/2 (up to
float rounding) as the method requires: the edge, with half the ball on each plane, is the
lowest point. PCA normals over 0.1 m round the edge (their zeta lies between the two planes'),
which lifts the zeta of the points near it; hence {share_1} % rather than {ideal_share} %.

**A cloud without a sensor origin.** A file format without a viewpoint (an XYZ file, a PLY
without the `sensor_origin` comment) gives the cloud the origin (0, 0, 0). For this corner that
point lies in the wall's plane, where "towards the sensor" cannot choose a side: the wall's
normals then take both signs by the rounding of the PCA, and zeta falls far below sqrt(2)/2
(the rows "origin (0, 0, 0)", the same files with the comment removed). Give such clouds their
viewpoint (a PCD's VIEWPOINT, the PLY comment) or score them in a frame whose origin is the
sensor.
"""


# ---------------------------------------------------------------------------- Fig. 5: the ramp

RAMP_REGIONS = [  # (name, test on x, y, z); geometry of libs/sim/include/upd/sim/scenes.h
    ("ground, d_m from the ramp", lambda x, y, z: z < 0.02 and (x < -0.6 or abs(y) > 1.3)),
    ("lower border, centre (|x| < 0.1, |y| < 0.2)", lambda x, y, z: abs(x) < 0.1 and abs(y) < 0.2),
    ("ramp body, centre (0.55 < x < 1.45, |y| < 0.2)", lambda x, y, z: 0.55 < x < 1.45 and abs(y) < 0.2),
    ("upper border, centre (|x - 2| < 0.1, |y| < 0.2)", lambda x, y, z: abs(x - 2) < 0.1 and abs(y) < 0.2),
    ("ramp and platform top, < d_m from a side (0.3 < |y| < 0.75)",
     lambda x, y, z: 0 < x < 3 and 0.3 < abs(y) < 0.75 and z > 0.02),
    ("whole scene", lambda x, y, z: True),
]


def ramp_section(work, fig):
    upd = read_ply(os.path.join(work, "ramp-upd.ply"), ["x", "y", "z", "scalar_zeta", "scalar_label"])
    rough = read_ply(os.path.join(work, "ramp-roughness.ply"), ["x", "y", "z", "scalar_label", "scalar_cost"])
    rj = json.load(open(os.path.join(work, "ramp-roughness.json")))
    uj = json.load(open(os.path.join(work, "ramp-upd.json")))
    caution = uj["params"]["classify"]["zeta_caution"]
    zeta_min = uj["params"]["classify"]["zeta_min"]
    rmax = rj["roughness_max_m"]
    rows = []
    body_rough = []
    for name, test in RAMP_REGIONS:
        sel = [i for i, (x, y, z) in enumerate(zip(upd["x"], upd["y"], upd["z"])) if test(x, y, z)]
        rsel = [i for i, (x, y, z) in enumerate(zip(rough["x"], rough["y"], rough["z"])) if test(x, y, z)]
        z = [upd["scalar_zeta"][i] for i in sel]
        flagged = sum(1 for v in z if v < caution)
        nt_upd = sum(1 for i in sel if upd["scalar_label"][i] == 1)
        nt_rough = sum(1 for i in rsel if rough["scalar_label"][i] == 1)
        if name.startswith("ramp body"):
            body_rough = sorted(rough["scalar_cost"][i] * rmax for i in rsel)
        zs = sorted(finite(z))
        rows.append([name, len(sel), "%.3f" % quantile(zs, 0.0), f1(pct(flagged, len(sel))),
                     f1(pct(nt_upd, len(sel))), f1(pct(nt_rough, len(rsel)))])
    d = rj["radius_m"]
    expected = math.tan(math.radians(20)) * d / 2
    head = ["region", "points", "min zeta", "UPD flagged (zeta < %g) [%%]" % caution,
            "UPD non-traversable [%]", "roughness non-traversable (> %g m) [%%]" % rmax]
    return f"""## Fig. 5: a 20 deg ramp, the UPD against the roughness index

The generated ramp (`upd scene ramp`): flat ground, a 20 deg ramp 1.5 m wide rising 2 m along
+x, a platform 0.73 m high. Both methods use the same d_m = {d:g} m ball and the default
pre-processing (2 cm voxels, outlier filter); the roughness index is the standard deviation of
elevation over the ball (`upd baseline`), non-traversable above {rmax:g} m.

{image(fig, "ramp-zeta.png", "ramp, zeta")}
{image(fig, "ramp-upd-label.png", "ramp, UPD label")}
{image(fig, "ramp-roughness-label.png", "ramp, roughness index label")}

{table(head, rows)}

The UPD sees the ramp's body as a plane (zeta = 1 whatever the slope: all normals agree) and
only flags its borders, where the ball holds two planes at 20 deg (zeta >= cos 10 deg = 0.985,
above zeta_min = {zeta_min:g}: flagged, cost > 0, traversable). The roughness index reads the
smooth body as rough: a plane tilted by 20 deg has an elevation spread of tan(20 deg) d_m / 2 =
{expected:.3f} m over a disc of radius d_m, and we measure a median of
{quantile(body_rough, 0.5):.3f} m on the body's centre (threshold {rmax:g} m): all of it
non-traversable. This is the paper's Fig. 5 contrast, and why `upd navigate --scenario ramp
--obstacles roughness` never climbs the ramp.

The generated ramp is 1.5 m wide and stands on vertical sides up to 0.73 m tall; within d_m of a
side the ball holds the side face at a right angle, and the UPD labels the ramp's top there
non-traversable (the row "< d_m from a side"): the edge of a drop, which both methods flag. The
ground next to the sides is flagged for the same reason. Only a strip about 0.5 m wide along
the ramp's middle is farther than d_m from both sides: that is where the two methods part.
"""


# ---------------------------------------------------------------------------- real frames

def frame_rows(work, frames):
    rows = []
    for name, file, up, cfg, d, what in frames:
        j = json.load(open(os.path.join(work, "data", name + ".json")))
        z = sorted(finite(read_ply(os.path.join(work, "data", name + ".ply"), ["scalar_zeta"])["scalar_zeta"]))
        lab = j["labels"]
        n = lab["traversable"] + lab["non_traversable"] + lab["unknown"]
        knn = j["params"]["upd"]["knn"]
        rows.append([name, "`%s`" % file, what, "`%s`" % up, "`%s`" % cfg,
                     ("k = %d" % knn) if knn else "%s m" % d, j["points_in"], n,
                     f1(pct(lab["traversable"], n)), f1(pct(lab["non_traversable"], n)),
                     f1(pct(lab["unknown"], n)), "%.3f" % quantile(z, 0.05), "%.3f" % quantile(z, 0.5)])
    return rows


def ground_truth_line(work):
    scored = os.path.join(work, "data", "hillside.ply")
    truth = os.path.join(work, "data", "hillside-ground.ply")
    if not (os.path.exists(scored) and os.path.exists(truth)):
        return ""
    g = read_ply(truth, ["x", "y", "z"])
    ground = set(zip(g["x"], g["y"], g["z"]))
    s = read_ply(scored, ["x", "y", "z", "scalar_label"])
    counts = {(True, 0): 0, (True, 1): 0, (False, 0): 0, (False, 1): 0}
    for x, y, z, lab in zip(s["x"], s["y"], s["z"], s["scalar_label"]):
        if lab in (0, 1):
            counts[((x, y, z) in ground, lab)] += 1
    gt, ob = counts[(True, 0)] + counts[(True, 1)], counts[(False, 0)] + counts[(False, 1)]
    return f"""
Against the bare-earth reference of the hillside (`samp11-utm-ground.pcd`, points matched by
their coordinates): of {gt} scored ground points {f1(pct(counts[(True, 0)], gt))} % are labelled
traversable; of {ob} object points (buildings, vegetation) {f1(pct(counts[(False, 1)], ob))} % are
labelled non-traversable. Steep bare ground is non-traversable for the robot (slope > 20 deg), so
the first number is not expected to reach 100 %; at about one point per square metre the
k-nearest ball spans several metres, so a low object is often seen as part of the slope.
"""


def frames_section(work, fig, data, quick):
    path = os.path.join(work, "frames.txt")
    frames = [l.rstrip("\n").split("|") for l in open(path)] if os.path.exists(path) else []
    if not frames:
        return f"""## Fig. 6 and the outdoor scenes: real frames

**Skipped**: the real sensor data (`{data}`) was not found when this report was made. Give
`scripts/results.sh --data DIR` the folder described by its `SOURCES.md`.
"""
    head = ["name", "file", "sensor, scene", "up", "config", "d_m", "points in", "scored",
            "traversable [%]", "non-trav. [%]", "unknown [%]", "zeta p5", "zeta median"]
    parts = [f"""## Fig. 6 and the outdoor scenes: real frames

Unmodified frames from `../shared/data` (origin and licence of each in its `SOURCES.md`), each
scored by `upd analyze` with the robot config named (`config/`), its up vector in the frame of
the file (a camera's optical frame: the floor normal) and d_m; the table's shares are of the
scored points. The paper's Fig. 6 shows indoor Kinect frames: RGB, normals and zeta.
{"(`--quick`: one frame only.)" if quick else ""}

{table(head, frame_rows(work, frames))}
{ground_truth_line(work)}"""]
    for name, file, up, cfg, d, what in frames:
        imgs = []
        for suffix, alt in [("rgb.png", "camera colour"), ("label.png", "label"),
                            ("zeta.png", "zeta")]:
            if os.path.exists(os.path.join(fig_abs(work), name + "-" + suffix)):
                imgs.append(image(fig, name + "-" + suffix, name + ", " + alt))
        parts.append("### %s: %s (`%s`)\n\n%s\n" % (name, what, file, "\n".join(imgs)))
    parts.append("""The stereo pairs in the shared data (`pcl/stereo_left.pcd` and `stereo_right.pcd`,
an outdoor car; `rtabmap/stereo_rect`, an indoor hall) are images without depth: they need a
disparity matcher (the `upd live --sensors` stereo route, docs/SENSORS.md) and are not scored
here. `stair-perception/0000_cloud.pcd` holds stale points where its depth is invalid
(SOURCES.md) and is left out.
""")
    return "\n".join(parts)


FIG_ABS = {}


def fig_abs(_work):
    return FIG_ABS["path"]


# ---------------------------------------------------------------------------- evaluation

def repository_paths(text, folder, fig):
    text = text.replace(os.path.abspath(folder), fig + "/evaluation")
    text = re.sub(r"/\S*/share/upd-nav/models/", "share/models/", text)
    return re.sub(r"upd evaluate --output \S*/evaluation([`\"])", r"upd evaluate --output %s/evaluation\1" % fig, text)


def evaluation_section(out, fig, status):
    head = "## Labelled evaluation\n\n"
    if status == "absent":
        return head + ("**Not run**: the `upd` that made this report has no `evaluate` command "
                       "(`upd help` does not list it).\n")
    if status == "quick":
        return head + "Not run with `--quick`.\n"
    if status == "failed":
        return head + "**Failed**: `upd evaluate --output` exited with an error (see the script's output).\n"
    folder = os.path.join(out, fig, "evaluation")
    md_path = os.path.join(folder, "evaluation.md")
    if not os.path.exists(md_path):
        return head + "**Missing**: `upd evaluate` wrote no `evaluation.md`.\n"
    prefix = fig + "/evaluation/"
    # Machine-specific paths (the staging folder, the build's classifier) as the repository's,
    # in the files kept beside the report as in the text included in it.
    for name in ("evaluation.md", "evaluation.json"):
        path = os.path.join(folder, name)
        if os.path.exists(path):
            kept = repository_paths(open(path).read(), folder, fig)
            with open(path, "w") as f:
                f.write(kept)
    text = open(md_path).read()
    # Relative links of the included file point into its folder.
    text = re.sub(r"(\]\()(?![a-z]+:|/|#)", r"\1" + prefix, text)
    pngs = sorted(p for p in os.listdir(folder) if p.endswith(".png"))
    missing = [p for p in pngs if (prefix + p) not in text]
    links = "".join("\n%s" % image(fig + "/evaluation", p, p[:-4]) for p in missing)
    # Demote the included headings below this section's.
    text = re.sub(r"^(#+) ", lambda m: "##" + m.group(1) + " ", text, flags=re.M)
    return (head + "From `upd evaluate --output %s/evaluation`, included as it wrote it:\n\n" % fig
            + text.strip() + "\n" + links + "\n")


# ---------------------------------------------------------------------------- the report

def report(a):
    FIG_ABS["path"] = os.path.join(a.out, a.figures)
    work, fig = a.work, a.figures
    sections = [
        "# Results: the paper reproduced\n",
        "Generated by `scripts/results.sh%s` from the `upd` commands' outputs (`upd scene`, "
        "`analyze`, `baseline`, `render`, `histogram`, `evaluate`); every number below is "
        "computed by `scripts/results_report.py` from those files. Paper: Bellone, Reina, "
        "Giannoccaro, Spedicato, *Unevenness Point Descriptor for Terrain Analysis in Mobile "
        "Robot Applications*, IJARS 2013. Colours: zeta from green (1, a plane) to blue "
        "(sqrt(2)/2, a right-angle edge; docs/FIGURES.md); labels green traversable, red "
        "non-traversable, grey unknown.\n" % (" --quick" if a.quick == "1" else ""),
        corner_section(work, fig, a.quick == "1"),
        ramp_section(work, fig),
        frames_section(work, fig, a.data, a.quick == "1"),
        evaluation_section(a.out, fig, a.eval),
    ]
    text = "\n".join(sections)
    dst = os.path.join(a.out, "RESULTS.md")
    tmp = dst + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, dst)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--has-colour")
    p.add_argument("--strip-origin", nargs=2)
    p.add_argument("--work")
    p.add_argument("--figures")
    p.add_argument("--out")
    p.add_argument("--eval", default="absent")
    p.add_argument("--quick", default="0")
    p.add_argument("--data", default="")
    a = p.parse_args()
    if a.has_colour:
        return 0 if any(n == "red" for _, n in ply_header(a.has_colour)[0]) else 1
    if a.strip_origin:
        strip_origin_copy(*a.strip_origin)
        return 0
    report(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
