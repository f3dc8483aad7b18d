"""``workcal simulate``: a virtual scene and scans of it, with the ground truth, for tests, demos and studies."""
from __future__ import annotations

from pathlib import Path

from workcal_wb.cli import EXIT_OK
from workcal_wb.cli.arguments import count, non_negative, positive, seed
from workcal_wb.core import frames
from workcal_wb.core.atomic import atomic_write_text
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.outputs import OutputFolder
from workcal_wb.core.simulate.scanner import scanner_ring
from workcal_wb.core.simulate.scene import build_scene
from workcal_wb.core.simulate.toolpath_sample import sample_toolpath
from workcal_wb.core.simulate.truth import scene_truth, write_truth
from workcal_wb.core.toolpath import format_gcode
from workcal_wb.core.writers import write_ply

# What a simulation writes into --out; a new run replaces all of it (fewer scan positions too).
OUTPUTS = ("scan.ply", "scan_*.ply", "workpiece.ply", "reference.ply", "toolpath.nc", "truth.json")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "simulate", help="simulate a scene (platform, L-block, workpiece) and scan it, with the true U, V, W",
        description="Build the paper's scene in the robot base frame B, scan it with a virtual structured-light "
                    "scanner from one or more positions, and write the scans (points in the scanner frame S), "
                    "the workpiece model X-A, the reference model B-P, a sample finishing toolpath in X (toolpath.nc) and truth.json (U, V, W, ^B S).")
    p.add_argument("--out", required=True, metavar="DIR", help="folder to write into (created if missing)")
    p.add_argument("--workpiece", choices=["car", "figurine"], default="car",
                   help="the 25 cm car model or the 2 cm figurine (default car)")
    p.add_argument("--seed", type=seed, default=0, help="seed for the workpiece pose, scanner placement and noise")
    p.add_argument("--positions", type=count, default=1, metavar="K",
                   help="scanner positions spread around the scene (default 1: the standard set-up)")
    p.add_argument("--noise", type=non_negative, metavar="MM", help="noise sigma along the ray (default 0.1 mm)")
    p.add_argument("--pitch", type=positive, metavar="MM",
                   help="sample spacing at the focus distance (default: zoomed to fit workpiece and reference)")
    p.add_argument("--clutter", action="store_true", help="also put a loose box and a cylinder on the platform")
    p.add_argument("--lump", action="store_true", help="add a clay lump to the workpiece after its model was made")
    p.add_argument("--carve", action="store_true", help="carve a patch out of the workpiece after its model was made")
    return p


def run(args) -> int:
    edits = [kind for kind, wanted in (("lump", args.lump), ("carve", args.carve)) if wanted]
    with OutputFolder(args.out, "simulate", OUTPUTS) as outputs:
        scene, scans = write_simulation(outputs.folder(), args.workpiece, seed=args.seed, positions=args.positions,
                                        noise=args.noise, pitch=args.pitch, clutter=args.clutter, clay_change=edits)
        outputs.commit("ok")
    _print_summary(scene, scans, Path(args.out))
    return EXIT_OK


def write_simulation(out: Path, workpiece: str = "car", *, seed: int = 0, positions: int = 1, noise=None, pitch=None,
                     clutter: bool = False, clay_change=()):
    """Simulate and write scan(s), workpiece.ply (X-A), reference.ply (B-P), toolpath.nc (X-m) and truth.json."""
    out.mkdir(parents=True, exist_ok=True)
    scene = build_scene(workpiece, seed=seed, clutter=clutter, clay_change=list(clay_change))
    settings = {"noise_sigma_mm": noise} if noise is not None else {}
    if pitch is not None:
        settings["pixel_pitch_mm"] = pitch
    scans = []
    for i, scanner in enumerate(scanner_ring(scene, positions, seed=seed, **settings), start=1):
        result = scanner.scan(scene)
        name = "scan.ply" if positions == 1 else f"scan_{i}.ply"
        write_ply(out / name, Cloud(result.points, name=name))
        scans.append((name, result))
    write_ply(out / "workpiece.ply", scene.workpiece_model())
    write_ply(out / "reference.ply", scene.reference_model())
    atomic_write_text(out / "toolpath.nc", format_gcode(sample_toolpath(scene)))
    write_truth(out / "truth.json", scene_truth(scene, scans))
    return scene, scans


def _print_summary(scene, scans, out: Path) -> None:
    W = scene.W
    phi, theta, psi = frames.euler_zyz(W)
    print(f"workpiece {scene.workpiece_original.name} (seed {scene.seed})"
          + (f", clay changed at {int(scene.reshaped.changed.sum())} vertices" if scene.reshaped else ""))
    print("W = ^B X:")
    for row in W:
        print("  " + " ".join(f"{v:12.5f}" for v in row))
    print(f"  Omega {frames.omega(W):.3f} deg, Euler ZYZ {phi:.3f} {theta:.3f} {psi:.3f} deg")
    for name, result in scans:
        counts = ", ".join(f"{role} {n}" for role, n in result.counts().items())
        print(f"{name}: {len(result.points)} points ({counts}), pitch {result.scanner.pixel_pitch_mm:.3f} mm, "
              f"Omega U {frames.omega(result.U):.2f} deg, V {frames.omega(result.V):.2f} deg")
    print(f"wrote {out}: {', '.join(name for name, _ in scans)}, workpiece.ply, reference.ply, toolpath.nc, truth.json")
