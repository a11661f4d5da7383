#!/usr/bin/env python3
"""test_mpi_pvtu.py - the vtk output of `floe run` under mpirun is a parallel series
(docs/parallel.md): each rank writes PREFIX_NNNNNN_R.vtu with the particles it owns (id = the
global particle id), rank 0 writes PREFIX_NNNNNN.pvtu naming the pieces and PREFIX.pvd listing
the .pvtu files.

Runs tests/mpi/pvtu.yaml (240 particles settling between 5 walls, in contact from the first step, 2,000 steps) once with
`floe run` on one process and under `mpirun -np K`, then reads every frame back (the VTK XML
parsed here: raw appended binary or ASCII, no VTK module needed) and checks:
  - the .pvd lists the .pvtu files, one per serial .vtu frame, at the serial times;
  - each .pvtu names exactly the K pieces PREFIX_NNNNNN_0..K-1.vtu, they all exist, and no
    other piece or serial-style frame file is in the directory;
  - the .pvtu declares the arrays (name, type, components) that every piece holds;
  - every particle id appears exactly once over the pieces, and the ids are those of the
    serial frame (walls left out, as the serial writer does);
  - Points, velocity and id-matched positions and velocities agree with the serial frame
    within 1e-9 of the array's largest magnitude (the split run sums contact forces in
    another order: round-off only over this horizon).
Cases: vtk + energy (rank 0's mirror writes energy.csv) at K = 2 and 4; vtk alone (ASCII,
every 0.93 ms of simulated time: 8 frames, the last one the final state written at the end)
at K = 4, where no state may be gathered on rank 0 (the traffic line's output bytes per step and
rank: at most the 4-byte word rank 0 broadcasts, no particle state).
Negative controls: a removed piece and a piece replaced by another rank's (duplicate ids)
must each be found by the same checks.

Usage: test_mpi_pvtu.py FLOE MPIEXEC TESTS_MPI_DIR
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

floe, mpiexec, here = sys.argv[1], sys.argv[2], sys.argv[3]
SCENE = os.path.join(here, "pvtu.yaml")
TOL = 1e-9
fails = 0
TYPES = {"Int32": ("i", 4), "Int64": ("q", 8), "Float64": ("d", 8), "UInt8": ("B", 1)}


def report(ok, what):
    global fails
    fails += not ok
    print(f"  {'ok  ' if ok else 'FAIL'} {what}")


def run(scene, outdir, np_):
    cmd = [floe, "run", scene, "-o", outdir]
    if np_ > 1:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(np_)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
        sys.exit(f"FAIL: {' '.join(cmd)} exited {r.returncode}")
    return r.stdout


def read_vtu(path):
    """{name: (type, ncomp, [tuples])} of the point data and Points of a .vtu written by floe"""
    data = open(path, "rb").read()
    cut = data.find(b"<AppendedData")
    head = data[:cut] + b"</VTKFile>\n" if cut >= 0 else data
    root = ET.fromstring(head)
    blob = b""
    if cut >= 0:
        start = data.index(b"_", data.index(b">", cut)) + 1
        blob = data[start:]
    piece = root.find("UnstructuredGrid/Piece")
    n = int(piece.get("NumberOfPoints"))
    out = {}
    for parent in ("PointData", "Points"):
        for da in piece.find(parent).findall("DataArray"):
            t, nc = da.get("type"), int(da.get("NumberOfComponents", "1"))
            code, size = TYPES[t]
            if da.get("format") == "appended":
                off = int(da.get("offset"))
                (nbytes,) = struct.unpack_from("<Q" if root.get("byte_order") == "LittleEndian" else ">Q", blob, off)
                if nbytes != n * nc * size:
                    raise ValueError(f"{path}: {da.get('Name')} holds {nbytes} bytes, not {n * nc * size}")
                vals = list(struct.unpack_from(("<" if root.get("byte_order") == "LittleEndian" else ">")
                                               + code * (n * nc), blob, off + 8))
            else:
                vals = [float(v) if t == "Float64" else int(v) for v in (da.text or "").split()]
                if len(vals) != n * nc:
                    raise ValueError(f"{path}: {da.get('Name')} holds {len(vals)} values, not {n * nc}")
            out[da.get("Name")] = (t, nc, [tuple(vals[k * nc:(k + 1) * nc]) for k in range(n)])
    return out


def read_pvtu(path):
    root = ET.parse(path).getroot()
    g = root.find("PUnstructuredGrid")
    decl = {}
    for parent in ("PPointData", "PPoints"):
        for da in g.find(parent).findall("PDataArray"):
            decl[da.get("Name")] = (da.get("type"), int(da.get("NumberOfComponents", "1")))
    return decl, [p.get("Source") for p in g.findall("Piece")]


def read_pvd(path):
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.find("Collection").findall("DataSet")]


def by_id(arrays):
    ids = [t[0] for t in arrays["id"][2]]
    return {i: {k: v[2][a] for k, v in arrays.items()} for a, i in enumerate(ids)}


def check_frame(outdir, pvtu, k, ref):
    """problems of one parallel frame against the serial frame ref (read_vtu)"""
    bad = []
    decl, sources = read_pvtu(os.path.join(outdir, pvtu))
    stem = pvtu[:-len(".pvtu")]
    want = [f"{stem}_{r}.vtu" for r in range(k)]
    if sources != want:
        bad.append(f"{pvtu} names {sources}, not {want}")
    seen = {}
    for src in sources:
        path = os.path.join(outdir, src)
        if not os.path.exists(path):
            bad.append(f"{pvtu}: piece {src} is missing")
            continue
        arrays = read_vtu(path)
        got = {name: (t, nc) for name, (t, nc, _) in arrays.items()}
        if got != decl:
            bad.append(f"{src} holds arrays {got}, the .pvtu declares {decl}")
        for i, rec in by_id(arrays).items():
            if i in seen:
                bad.append(f"{pvtu}: id {i} in {seen[i][0]} and {src}")
            seen[i] = (src, rec)
    serial = by_id(ref)
    if sorted(seen) != sorted(serial):
        bad.append(f"{pvtu}: ids {sorted(set(seen) ^ set(serial))[:10]} are not in both the pieces and the serial frame")
    worst = 0.0
    for name in ("Points", "velocity", "angular_velocity", "force", "radius"):
        scale = max([abs(c) for rec in serial.values() for c in rec[name]] + [1e-300])
        for i, rec in serial.items():
            if i in seen:
                d = max(abs(a - b) for a, b in zip(rec[name], seen[i][1][name])) / scale
                worst = max(worst, d)
    if worst > TOL:
        bad.append(f"{pvtu}: positions or velocities differ from the serial run by {worst:.2e} of the scale")
    return bad, worst


def check_run(ref_dir, outdir, k, prefix="frame"):
    serial = read_pvd(os.path.join(ref_dir, prefix + ".pvd"))
    par = read_pvd(os.path.join(outdir, prefix + ".pvd"))
    report(len(par) == len(serial) and all(f == s[:-len(".vtu")] + ".pvtu" and abs(t - ts) <= 1e-12 * max(1, abs(ts))
                                           for (t, f), (ts, s) in zip(par, serial)),
           f"{prefix}.pvd lists {len(par)} .pvtu frames at the serial run's {len(serial)} times")
    listed = {f for _, f in par}
    expect = listed | {f[:-len(".pvtu")] + f"_{r}.vtu" for f in listed for r in range(k)}
    frames = {n for n in os.listdir(outdir) if re.fullmatch(re.escape(prefix) + r"_\d{6}(_\d+)?\.p?vtu", n)}
    report(frames == expect, f"the directory holds exactly the {len(listed)} .pvtu and their {k} pieces each"
           + ("" if frames == expect else f" (extra {sorted(frames - expect)[:5]}, missing {sorted(expect - frames)[:5]})"))
    worst, problems = 0.0, []
    for (_, f), (_, s) in zip(par, serial):
        bad, w = check_frame(outdir, f, k, read_vtu(os.path.join(ref_dir, s)))
        problems += bad
        worst = max(worst, w)
    for p in problems[:10]:
        print("    " + p)
    report(not problems, f"{len(par)} frames: every id once over the pieces, arrays as declared; positions and "
           f"velocities within {worst:.2e} of the serial run's (tol {TOL:g})")
    return par


def negative_controls(ref_dir, outdir, k, par):
    """a missing piece and a duplicated piece must be found"""
    with tempfile.TemporaryDirectory() as tmp:
        d = os.path.join(tmp, "copy")
        shutil.copytree(outdir, d)
        _, f = par[-1]
        _, s = read_pvd(os.path.join(ref_dir, "frame.pvd"))[-1]
        ref = read_vtu(os.path.join(ref_dir, s))
        stem = f[:-len(".pvtu")]
        os.remove(os.path.join(d, f"{stem}_{k - 1}.vtu"))
        bad1, _ = check_frame(d, f, k, ref)
        shutil.copy(os.path.join(d, f"{stem}_0.vtu"), os.path.join(d, f"{stem}_{k - 1}.vtu"))
        bad2, _ = check_frame(d, f, k, ref)
    report(any("missing" in b for b in bad1) and any(" in " in b and "id " in b for b in bad2),
           "negative controls: a removed piece and a duplicated piece are both detected")


with tempfile.TemporaryDirectory() as tmp:
    ref = os.path.join(tmp, "np1")
    run(SCENE, ref, 1)
    for k in (2, 4):
        out = os.path.join(tmp, f"np{k}")
        print(f"pvtu.yaml (vtk + energy): mpirun -np {k} against one process:")
        run(SCENE, out, k)
        par = check_run(ref, out, k)
        report(os.path.exists(os.path.join(out, "energy.csv")), "energy.csv written (rank 0's mirror)")
        if k == 4:
            negative_controls(ref, out, k, par)
    # vtk alone, ASCII: no mirror, no gather
    text = open(SCENE).read()
    text = re.sub(r"outputs:\n(  - .*\n)+", "outputs:\n  - {type: vtk, interval: 0.00093, prefix: frame, ascii: true}\n", text)
    scene2 = os.path.join(tmp, "vtk_only.yaml")
    open(scene2, "w").write(text)
    ref2 = os.path.join(tmp, "np1_vtk")
    run(scene2, ref2, 1)
    out2 = os.path.join(tmp, "np4_vtk")
    print("vtk alone (ASCII, by interval): mpirun -np 4 against one process:")
    stdout = run(scene2, out2, 4)
    check_run(ref2, out2, 4)
    m = re.search(r"output ([0-9.]+) B\)", stdout)
    report(m is not None and float(m.group(1)) <= 4.0,
           f"no state gathered on rank 0: output traffic {m.group(1) if m else '?'} B per step and rank (<= 4)")
    report(sorted(os.listdir(out2)) == sorted(n for n in os.listdir(out2) if n.startswith("frame")),
           "only the vtk series in the output directory")
print(f"test_mpi_pvtu: {fails} failed")
sys.exit(1 if fails else 0)
