"""Scenes as a real cell gives them: any export frame, touching and clay-bridged objects,
views where a rival pose of the reference fits as well as the right one.  Each scene is simulated by
simulate.cell with exact truth; every calibration uses automatic regions."""
import numpy as np
import pytest

from workcal_wb.core import calibration, frames, physics, pointops
from workcal_wb.core.edges import centre_on_edges
from workcal_wb.core.regions import CLUSTERS, _clusters, find_platform, near_points
from workcal_wb.core.surface import SurfaceModel
from workcal_wb.core.calibration import CalibrationOptions, calibrate
from workcal_wb.core.errors import Stopped
from workcal_wb.core.geometry import Cloud
from workcal_wb.core.result import (DISTORTION, MANY_WAYS, MISFIT, RIVAL, SEARCH_DOUBT, SPLIT_UNEXPLAINED, Candidate,
                                     Reason, codes)
from workcal_wb.core.simulate import shapes
from workcal_wb.core.simulate.cell import CellSpec, cell_scan



def _errors(W, truth, model):
    """(rotation deg, largest displacement of a model point mm) of W against the truth."""
    moved = np.linalg.norm(frames.apply(W, model.points) - frames.apply(truth, model.points), axis=1)
    return frames.rotation_between_deg(W, truth), float(moved.max())


_PREPARED = {}


def _prepared(model, seed: int) -> SurfaceModel:
    """One prepared model per model and seed for the whole module: the scenes share the car and the
    L-block, so each is prepared (and its nearest-point grid filled) once, not per calibration."""
    key = (model.points.tobytes(), None if model.triangles is None else model.triangles.tobytes(), seed)
    if key not in _PREPARED:
        _PREPARED[key] = SurfaceModel(model, seed)
    return _PREPARED[key]


def _calibrated(cell, **options):
    seed = options.get("seed", 0)
    return calibrate(cell.cloud, _prepared(cell.workpiece_model, seed), _prepared(cell.reference_model, seed),
                     options=CalibrationOptions(resamples=2, **options))


@pytest.mark.slow
def test_scan_exported_in_a_table_frame_with_its_origin_under_the_table():
    """Failure 1 of the issue: "up" was taken towards the scan's origin, so a scan in a table frame
    whose origin lies under the table lost every point as "below the platform"."""
    cell = cell_scan(CellSpec(frame="table", seed=1))
    assert cell.platform_height_over_origin() > 0  # the origin lies under the table
    result = _calibrated(cell)
    assert result.status == "ok", result.reasons
    rotation, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert rotation < 0.05 and displacement < 0.1


@pytest.mark.slow
def test_a_whole_scene_moved_by_any_rigid_motion_calibrates_to_the_same_W():
    cell = cell_scan(CellSpec(seed=2))
    first = _calibrated(cell)
    assert first.status == "ok", first.reasons
    rng = np.random.default_rng(11)
    for _ in range(5):
        moved = cell.moved(frames.random_motion(rng, shift_mm=3000.0))
        again = _calibrated(moved)
        rotation, displacement = _errors(again.W, first.W, cell.workpiece_model)
        assert again.status == "ok" and rotation < 0.01 and displacement < 0.01, (rotation, displacement)


@pytest.mark.slow
@pytest.mark.parametrize("layout, seed, frame, statuses", [
    ("touching", 0, "sensor", ("ok",)), ("bridge", 0, "sensor", ("ok", "ambiguous")),
    ("touching", 1, "arbitrary", ("ok", "ambiguous")), ("touching", 4, "arbitrary", ("ok", "ambiguous"))])
def test_touching_or_bridged_objects_are_split_by_their_models(layout, seed, frame, statuses):
    """Failure 2 of the issue: touching objects (or clay joining them) fall into one cluster, which
    neither model explained, so neither was found.  Seeds 1 and 4: the L-block placed through the
    platform explained one arm of the pair and passed for the reference (found 120 and 180 deg off;
    now such a pose locates nothing); then the block, partly hidden by the workpiece, was called
    free to slide (few points lie along its edges) or its surface "went on past its outline" on faces
    seen grazing (see visibility.evidence).  With 2 bootstrap refits the outline test may still find
    3 % there (its limit): ambiguous is allowed, a wrong W or region is not.  Bridge seed 0: once the
    workpiece is placed, the global search on the block with the clay left on it proposes the right
    pose in 1 of 8 seeds on either stack (the half turned block explains 70 % of those points); on
    FreeCAD 1.0's stack (numpy 2, scipy 1.15, open3d 0.19, its scan differing by rounding) none of the
    3 seeds tried is that one, and the points of the pair it leaves unexplained make it ambiguous, never ok."""
    cell = cell_scan(CellSpec(layout=layout, seed=seed, frame=frame))
    result = _calibrated(cell)
    assert result.status in statuses, result.reasons
    if result.status != "ok" and SPLIT_UNEXPLAINED in codes(result.reasons):
        return  # the split is not trusted and says why: nothing of it is claimed
    rotation, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert rotation < 0.05 and displacement < 0.1
    assert any("touches another object" in w for w in result.warnings)
    for role, other in (("reference", "workpiece"), ("workpiece", "reference")):
        region = result.regions[role]
        assert not cell.mask(other)[region].any(), f"{other} points in the {role} region"
        own = cell.mask(role) | (cell.mask("bridge") if role == "workpiece" else False)  # clay joins the workpiece
        assert own[region].mean() > 0.97


@pytest.mark.slow
def test_a_rival_the_scan_alone_cannot_reject_is_ruled_out_by_free_space():
    """Failure 3 of the issue: seen low from one side, the L-block fits turned half round as well as
    the right way; from where the scanner stood, the turned block would stand where it saw through to
    the table behind.  The match alone calls it a tie; the calibration rules the rival out."""
    cell = cell_scan(CellSpec(azimuth_deg=180, elevation_deg=15, seed=7))
    result = _calibrated(cell, scanner_origin=tuple(cell.scanner_origin))
    assert result.status == "ok", result.reasons
    assert _errors(result.W, cell.W, cell.workpiece_model)[1] < 0.1
    decided = result.reference.constraints
    assert any("ruled out by free space" in c for c in decided), decided
    assert any(c.ruled_out_by == "free space" for c in result.reference.candidates)


def _with_sunk_rivals(monkeypatch, cell, count):
    """Calibrations whose reference match lists ``count`` rivals tied with the best: the best pose
    lowered 15, 20, 25 ... mm into the platform."""
    found = calibration._refit

    def refit(scan, idx, surface, first, matched, options, role):
        m = found(scan, idx, surface, first, matched, options, role)
        if role == "reference" and m.status == "ok":
            for k in range(count):
                sunk = frames.rigid(translation=-(15.0 + 5 * k) * cell.up) @ np.asarray(m.matrix)
                m.candidates.append(Candidate(sunk, rival=True))
            m.reasons.append(Reason(RIVAL, f"{count} clearly different pose(s) explain the view about as well"))
            m.ties.append(m.reasons[-1])
            m.status = "ambiguous"
        return m

    monkeypatch.setattr(calibration, "_refit", refit)


@pytest.mark.slow
def test_platform_contact_rules_out_rivals_that_sink_through_it(monkeypatch):
    cell = cell_scan(CellSpec(seed=3))
    _with_sunk_rivals(monkeypatch, cell, 2)
    result = _calibrated(cell, scanner_origin=tuple(cell.scanner_origin))
    assert result.status == "ok", result.reasons
    assert sum("ruled out by platform contact: it sinks" in c for c in result.reference.constraints) == 2
    assert frames.rotation_between_deg(result.V, cell.V) < 0.05


@pytest.mark.slow
def test_rivals_past_max_ruled_out_leave_the_tie_standing_though_all_sink(monkeypatch):
    """A view that fits the reference in many listed ways may fit it in one the search did not list."""
    cell = cell_scan(CellSpec(seed=3))
    _with_sunk_rivals(monkeypatch, cell, physics.MAX_RULED_OUT + 1)
    result = _calibrated(cell, scanner_origin=tuple(cell.scanner_origin))
    assert result.status == "ambiguous"
    assert MANY_WAYS in codes(result.reasons), result.reasons


@pytest.mark.slow
def test_a_search_ahead_the_reference_made_needless_is_stopped(monkeypatch):
    """Seen low, the workpiece's likeliest cluster is the L-block, which the reference takes: nothing
    waits for the workpiece's search of it on the second thread.  Here that search runs until it is
    told to stop: locate tells it once both objects are found, and the calibration is right."""
    from workcal_wb.core import regions

    told, search = [], regions._search

    def ahead_waits_to_be_stopped(*args, stop=None):
        if stop is None:  # a search in turn, on the main thread
            return search(*args)
        told.append(stop.wait(timeout=300))  # the search ahead: as long as it is let run
        raise Stopped("stopped")

    monkeypatch.setattr(regions, "_search", ahead_waits_to_be_stopped)
    cell = cell_scan(CellSpec(azimuth_deg=233.0, elevation_deg=22.0, frame="arbitrary", seed=3))
    result = _calibrated(cell)
    assert told == [True]
    assert result.status == "ok", result.reasons
    rotation, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert rotation < 0.05 and displacement < 0.1


@pytest.mark.slow
def test_a_cluster_that_holds_no_pose_of_the_reference_is_searched_once(monkeypatch):
    """With clay joining the objects, a small cluster beside them (594 points) is the reference's
    likeliest, and no pose of the L-block fits it within the noise.  Searched again, with other seeds
    or with more hypotheses, such a cluster never comes back with one (docs/tuning.md): it is searched
    once, one global search, and the calibration is right."""
    import collections
    import threading

    from workcal_wb.core import match as match_module, regions

    searched, original = [], regions.match  # (role, points, seed, misfit) of each search while locating
    drawn, local, draw = collections.Counter(), threading.local(), match_module._global_candidates

    def recorded(cloud, surface, *args, **kwargs):
        local.search = (cloud.name.split()[0], len(cloud.points), kwargs.get("seed"))
        result = original(cloud, surface, *args, **kwargs)
        searched.append((*local.search, MISFIT in codes(result.reasons)))
        return result

    def counted(*args, **kwargs):  # the global searches of each search (the threads search apart)
        drawn[local.search] += 1
        return draw(*args, **kwargs)

    monkeypatch.setattr(regions, "match", recorded)
    monkeypatch.setattr(match_module, "_global_candidates", counted)
    cell = cell_scan(CellSpec(layout="bridge", frame="arbitrary", seed=4))
    result = _calibrated(cell)
    misfits = [search for *search, misfit in searched if misfit]
    assert misfits, searched
    for role, points, seed in misfits:
        assert len([s for s in searched if s[:2] == (role, points)]) == 1, searched
        assert drawn[(role, points, seed)] == 1, (drawn, searched)
    assert result.status == "ok", result.reasons
    rotation, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert rotation < 0.05 and displacement < 0.1


def test_a_region_the_user_picked_is_searched_again_after_a_misfit(monkeypatch):
    """A misfit ends the searches of a cluster locate weighs (it may hold another object), and its match
    draws no second search; not those of a region the user picked, which holds the object: there the
    other seeds are tried, each match free to search again."""
    from workcal_wb.core import regions
    from workcal_wb.core.result import MatchResult

    seeds, searched_again = [], []  # each search's seed, and whether its match may search again itself

    def misfit(cloud, surface, stop=None, **options):
        seeds.append(options["seed"])
        searched_again.append(options["search_again"])
        pose = np.eye(4)
        pose[0, 3] = 10.0 * len(seeds)  # another pose each time
        return MatchResult("failed", "robust", pose, fitness=0.9,
                           reasons=[Reason(MISFIT, "the model does not fit the scan within its noise")])

    monkeypatch.setattr(regions, "match", misfit)
    cloud, model = Cloud(np.zeros((3, 3))), SurfaceModel(shapes.l_block())
    assert regions.match_trusted(cloud, model, {"seed": 0}, "reference", candidate=True).status == "failed"
    assert seeds == [0] and searched_again == [False]
    seeds.clear(), searched_again.clear()
    regions.match_trusted(cloud, model, {"seed": 0}, "reference")
    assert seeds == [0, 1, 2] and searched_again == [True] * 3


@pytest.mark.slow
def test_an_l_block_seen_low_from_its_outer_side_is_found_and_never_ok_turned_over():
    """Seen low from its outer side, the L-block calibrated "ok" with V 180 deg off
    (seeds 1 and 2 on Debian 12, seed 0 on Debian 13 on an AMD EPYC machine): the right pose's RANSAC
    hypothesis ranked 4th to 11th by its rough score among wrong turns and was never refined, and the
    platform ruled out the three rivals listed.  Rough poses are now taken a few steps first (match.
    SEARCH.pre_refined): the right pose is found with most seeds (4 of 4 on Debian 12, 3 of 4 on Debian 13 here);
    Debian 13's seed 3 still misses it and stays ambiguous (three rivals half a turn from its best: one
    sinks through the platform, two stand on it)."""
    cell = cell_scan(CellSpec(azimuth_deg=0, elevation_deg=20, seed=7))
    results = [_calibrated(cell, scanner_origin=tuple(cell.scanner_origin), seed=seed) for seed in range(4)]
    ok = [r for r in results if r.status == "ok"]
    assert all(frames.rotation_between_deg(r.V, cell.V) < 0.05 for r in ok), "ok with the reference turned over"
    assert len(ok) >= 2, [r.reasons for r in results]


def test_the_platform_seen_low_shows_its_side_face_and_is_still_found():
    """Seen 22 deg above the table, the platform's own front face lies under its plane: it was counted
    as objects below the plane, so no plane was a platform and the reference region took table points."""
    cell = cell_scan(CellSpec(azimuth_deg=89.0, elevation_deg=22.0, frame="arbitrary", seed=1))
    points = cell.cloud.points
    platform = find_platform(points, pointops.median_spacing(points, seed=0), np.random.default_rng(0))
    assert platform is not None and platform.up @ cell.up > 0.999
    below_top = cell.mask("platform") & (platform.height(points) < -platform.band)
    assert below_top.sum() > 1000  # the side face is in the scan
    assert platform.below[cell.mask("platform")].mean() > 0.95
    assert platform.below[cell.mask("reference")].mean() < 0.03
    # The clusters its size test split the objects into come with it, for the regions.
    spacing = pointops.median_spacing(points, seed=0)
    assert np.array_equal(platform.labels, _clusters(points[~platform.below], CLUSTERS.link_spacings * spacing))


def test_which_points_lie_near_a_placed_model_is_what_the_kd_tree_says():
    """regions.near_points asks the cell grid first and the KD-tree only where the grid leaves it open."""
    cell = cell_scan(CellSpec(seed=2))
    model = _prepared(cell.reference_model, 0)
    points = cell.cloud.points[np.isfinite(cell.cloud.points).all(axis=1)]
    U = frames.rigid(translation=[0.4, -0.3, 0.2]) @ cell.F_S @ frames.invert(cell.B_S)  # a little off the truth
    for distance in (0.3, 2.0, 3.0, 40.0):
        truth = model.nearest(frames.apply(frames.invert(U), points), distance)[2]
        assert 0 < truth.sum() < len(points)
        assert np.array_equal(near_points(points, model, U, distance), truth), distance


def test_a_block_partly_hidden_by_the_workpiece_it_touches_is_held_by_its_edges():
    """Where few scan points lie along the block's edges, sliding it 0.6 mm pushed too few of them off
    to stand above the count's jitter, and the slide was called free (under-constrained)."""
    cell = cell_scan(CellSpec(layout="touching", frame="arbitrary", seed=1))
    surface = _prepared(cell.reference_model, 0)
    points = cell.cloud.points[cell.mask("reference")]
    T = frames.invert(cell.V)
    centred, stability = centre_on_edges(points, surface, T, gate=1.0, sigma=0.066, tolerance_mm=0.3)
    assert stability["constrained"] and stability["held_by_edges"], stability
    assert np.linalg.norm(centred[:3, 3] - T[:3, 3]) < 0.1


@pytest.fixture(scope="module")
def bridge_scene():
    """The clay-bridge scene #3 of the scenes table's second seed set, calibrated as that table ran it."""
    cell = cell_scan(CellSpec(layout="bridge", frame="arbitrary", seed=1003))
    return cell, _calibrated(cell, seed=1)


@pytest.mark.slow
def test_a_split_that_leaves_much_of_the_touching_objects_unexplained_is_never_ok(bridge_scene):
    """Clay joining the objects, seen so that the L-block turned half round stands on the platform and
    explains 2285 of its 3077 points: that pose was reported ok, 180 deg off.  The points of the
    joined objects on neither model (1090) say the split may be wrong.  (Since then the search places
    the block upside down and its doubt is kept; see the next test.)"""
    cell, result = bridge_scene
    if result.status == "ok":
        assert _errors(result.W, cell.W, cell.workpiece_model)[1] < 0.3
    else:
        assert {SPLIT_UNEXPLAINED, SEARCH_DOUBT} & set(codes(result.reasons)), result.reasons


@pytest.mark.slow
def test_a_refit_that_moves_from_the_searched_pose_says_whose_doubt_it_keeps(bridge_scene):
    """The scene above: whatever its reference search settles on, W is right when it is "ok".  And a
    refit that moves from the pose an ambiguous search placed the block in (its region picked with
    that pose: here the block turned half round about the vertical, its doubt "a doubt") to another
    pose keeps the doubt but says which pose it was about, not as if it were about the pose it now
    has (a right W, and points off "the placed model" that are not off it)."""
    from workcal_wb.core.geometry import Cloud
    from workcal_wb.core.regions import refit
    from workcal_wb.core.result import AMBIGUOUS, MatchResult
    from workcal_wb.core.symmetry import turn

    cell, result = bridge_scene
    rotation, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert result.status != "ok" or (rotation < 0.05 and displacement < 0.1), result.reasons
    block = cell.cloud.subset(np.flatnonzero(cell.mask("reference")))
    surface = _prepared(cell.reference_model, 1)
    centre = frames.apply(cell.V, cell.reference_model.points.mean(axis=0)[None])[0]
    found = MatchResult(AMBIGUOUS, matrix=turn(cell.up, 180.0, centre) @ cell.V, reasons=[Reason(RIVAL, "a doubt")],
                        method="robust", seed=1)
    again = refit(Cloud(block.points, name="block"), surface, found, {"seed": 1})
    assert frames.rotation_between_deg(again.matrix, cell.V) < 0.05  # the refit comes home
    assert again.status == "ambiguous"
    assert codes(again.reasons) == [SEARCH_DOUBT], again.reasons
    said = str(again.reasons[0])
    assert said.startswith("this pose was refined from a first pose 180 deg and") and "[a doubt]" in said


@pytest.mark.parametrize("seed", [0, 4])
def test_a_scene_without_a_platform_takes_no_face_of_an_object_for_one(seed):
    """No platform #0 and #4 of the scenes table: a face of an object, with the other object on one
    side of it, was taken for the platform; the points behind it went as "below the platform" and the
    sink check rejected the reference's right pose.  A platform is larger than what stands on it.
    Told which way is up, or where the scanner was (an E57 or PCD file says), a horizontal face of
    an object was still taken for one: a told side names which way is up, not which plane is the
    platform."""
    cell = cell_scan(CellSpec(platform="none", frame="arbitrary", seed=seed))
    points = cell.cloud.points
    spacing = pointops.median_spacing(points, seed=0)
    for hint in ({}, {"up": cell.up}, {"viewpoint": cell.scanner_origin}):
        assert find_platform(points, spacing, np.random.default_rng(0), **hint) is None, hint


def test_a_told_up_or_scanner_position_keeps_the_platform():
    """The same hints on a scene with a platform (in an arbitrary frame) find it, up the right way."""
    cell = cell_scan(CellSpec(frame="arbitrary", seed=2))
    points = cell.cloud.points
    spacing = pointops.median_spacing(points, seed=0)
    truth = cell.mask("platform")
    for hint in ({"up": cell.up}, {"viewpoint": cell.scanner_origin}):
        platform = find_platform(points, spacing, np.random.default_rng(0), **hint)
        assert platform.up @ cell.up > 0.999, hint
        assert platform.below[truth].mean() > 0.99 and truth[platform.below].mean() > 0.99, hint


def _distorted(cell, strain: np.ndarray, seed: int):
    """The scan as a scanner whose calibration is off by ``strain`` makes it (about the scanner, at the
    origin of a "sensor" frame scan), exported in a random frame; the truth W stays."""
    linear = np.eye(4)
    linear[:3, :3] += strain
    distorted = cell.moved(linear)
    return distorted.moved(frames.random_motion(np.random.default_rng(seed), shift_mm=3000.0))


@pytest.mark.slow
@pytest.mark.parametrize("seed, strain", [
    (0, np.diag([0.002, 0.002, 0.002])),  # 0.2 % too large
    (1, np.diag([-0.005, -0.005, -0.005])),  # 0.5 % too small
    (2, np.array([[0, 0.003, 0], [0, 0, 0], [0, 0, 0]])),  # x leans 0.3 % towards y
    (3, np.diag([0, 0, 0.003])),  # depth stretched 0.3 %
], ids=["larger", "smaller", "sheared", "deeper"])
def test_a_scan_distorted_by_its_scanner_fails_and_says_so(seed, strain):
    """A scanner whose calibration is 0.2-0.5 % off gave "ok" with W 0.4-1.5 mm
    off, because each object still fits its model within the tolerance, each placed about its own region,
    and W joins the two.  The scan's strain is measured (on the reference, and on both objects where the
    reference cannot show it), and how far it moves W."""
    cell = cell_scan(CellSpec(frame="sensor", seed=seed))
    result = _calibrated(_distorted(cell, strain, seed))
    _, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert displacement > 0.18  # what the gate is there for: W is off
    assert result.status == "failed"
    assert DISTORTION in codes(result.reasons), result.reasons
    u = result.uncertainty
    assert abs(u["distortion_scale_pct"] - 100 * np.trace(strain) / 3) < 0.03
    largest = 100 * np.abs(np.linalg.eigvalsh((strain + strain.T) / 2)).max()
    assert abs(u["distortion_strain_pct"] - largest) < 0.05
    assert 0.7 * displacement < u["distortion_shift_mm"] < 1.2 * displacement


@pytest.mark.slow
@pytest.mark.parametrize("seed, scale", [(1, 0.02), (2, -0.02)])
def test_a_scan_scaled_two_percent_is_refused_for_its_scale(seed, scale):
    """A 2 % scale put the reference's ends beyond the check's gate (twice the tolerance, 0.6 mm), its
    middle read no strain, and the workpiece's 2 % went as the part's own: the check read nothing, with W
    3.8-4.6 mm off (refused here for other reasons, by a hair).  The check's gates are at least the
    matches' own (it keeps every point a match was finished on), and no part differs from its model by a
    scale of 2 %."""
    cell = cell_scan(CellSpec(frame="sensor", seed=seed))
    result = _calibrated(_distorted(cell, np.eye(3) * scale, seed))
    _, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    u = result.uncertainty
    assert u["distortion_scale_pct"] == pytest.approx(100 * scale, rel=0.05), u
    assert u["distortion_shift_mm"] > 0.7 * displacement, (u, displacement)
    assert result.status == "failed" and DISTORTION in codes(result.reasons), result.reasons


@pytest.mark.slow
def test_a_scan_within_a_good_scanners_accuracy_stays_ok():
    """An undistorted scan and one 0.05 % too large (a good structured-light scanner's accuracy) are
    "ok", and W is off by no more than the distortion's share of the tolerance and the spread allow."""
    cell = cell_scan(CellSpec(frame="sensor", seed=4))
    for scale, largest in ((0.0, 0.02), (0.0005, 0.07)):
        result = _calibrated(_distorted(cell, np.eye(3) * scale, 4))
        assert result.status == "ok", (scale, result.reasons)
        u = result.uncertainty
        assert abs(u["distortion_scale_pct"] - 100 * scale) < 0.01 and u["distortion_strain_pct"] < largest
        _, displacement = _errors(result.W, cell.W, cell.workpiece_model)
        assert displacement < u["distortion_shift_mm"] + u["surface_bound_mm"], (scale, displacement, u)


@pytest.mark.slow
@pytest.mark.parametrize("seed, azimuth", [(1, 89.0), (3, 233.0)])
def test_a_real_range_scan_differing_from_its_model_is_not_a_distorted_scanner(bunny, seed, azimuth):
    """A real range scan of the bunny strains 0.3-0.5 % against the bunny's model (a range scan and the
    model zippered from several differ so).  Seen from here the reference shows few strains, and the
    bunny's, counted as the scanner's, moved W 0.3-0.5 mm: 4 of the 5 bunny scenes of the benchmark were
    refused with W right to 0.16 mm.  Along the strains the reference does show, it reads none and the
    bunny reads some: the bunny's strain is its own, and W stays "ok"."""
    cell = cell_scan(CellSpec(workpiece="bunny", frame="arbitrary", seed=seed, azimuth_deg=azimuth),
                     bunny_folder=bunny)
    result = _calibrated(cell)
    assert result.status == "ok", result.reasons
    _, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert displacement < 0.2 and result.uncertainty["distortion_shift_mm"] < 0.05
    assert any("taken as the part's own" in w for w in result.warnings), result.warnings


@pytest.mark.slow
@pytest.mark.parametrize("seed, azimuth", [(2, 120.0), (2, 240.0)])
def test_a_strain_the_reference_does_not_confirm_is_a_warning_not_a_refusal(bunny, seed, azimuth):
    """The bunny's real range scan touching the block, the scanner where the scan's origin is: the block
    shows one strain and reads none along it; the bunny reads 0.45 % against its zippered model along
    every strain, as a range scan and a model merged from several differ.  Taken as the scanner's, it
    "moved" W 0.29-0.38 mm and refused a right W.  Only a reference that shows a strain, or both objects
    reading it alike, make it the scanner's: here "ok", with a warning that gives the reading and how far
    W would move were it the scanner's."""
    cell = cell_scan(CellSpec(workpiece="bunny", layout="touching", frame="sensor", seed=seed, azimuth_deg=azimuth),
                     bunny_folder=bunny)
    result = _calibrated(cell, scanner_origin=tuple(cell.scanner_origin))
    assert DISTORTION not in codes(result.reasons), result.reasons
    _, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert displacement < 0.3 and result.uncertainty["distortion_shift_mm"] < 0.05
    assert result.uncertainty["distortion_unverified_shift_mm"] > 0.1
    warned = [w for w in result.warnings if "reference does not confirm" in w]
    assert warned and "were it the scanner's, W would move up to" in warned[0], result.warnings


@pytest.mark.slow
def test_an_undistorted_noisy_low_view_is_not_refused_for_distortion():
    """Found by random scenes varying what the scenes benchmark keeps fixed (noise, view, stray points):
    an undistorted car scene at 0.2 mm noise, the L-block seen low (25 deg), read a -0.16 %
    scale and a 0.32 % strain that no scanner made and "moved" W 0.70 mm, so the calibration failed
    with W right to 0.003 deg.  The check measured each point against its nearest sample's tangent
    plane, another face's near the block's edges, where noise along grazing rays puts points past the
    edge on one side, with the noisy point as its lever; on meshes it measures against the exact closest
    face away from its edges, and the lever is the point's foot (distortion.py)."""
    cell = cell_scan(CellSpec(frame="sensor", azimuth_deg=69.66992932758518, elevation_deg=25.473620413605275,
                              stray_fraction=0.02, noise_mm=0.2, seed=3015))
    result = _calibrated(cell)
    rotation, displacement = _errors(result.W, cell.W, cell.workpiece_model)
    assert rotation < 0.05 and displacement < 0.1  # W is right ...
    assert result.uncertainty["distortion_shift_mm"] < 0.1, result.uncertainty  # ... and no scanner distorted it
