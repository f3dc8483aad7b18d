"""FreeCAD layer under freecadcmd: scan objects, regions, setup and model clouds, read back from documents."""
import numpy as np
import pytest

FreeCAD = pytest.importorskip("FreeCAD")

import Mesh  # noqa: E402
import Part  # noqa: E402
import Points  # noqa: E402

from workcal_wb.core.errors import InputError  # noqa: E402
from workcal_wb.core.geometry import Cloud  # noqa: E402
from workcal_wb.core.writers import write_ply, write_xyz  # noqa: E402
from workcal_wb.fc import init as fc_init  # noqa: E402
from workcal_wb.fc import lookups, models, scan, setup  # noqa: E402


@pytest.fixture
def doc():
    """A new document; every document the test opened is closed afterwards (reopened ones too)."""
    before = set(FreeCAD.listDocuments())
    document = FreeCAD.newDocument("WorkCalScanTest")
    document.UndoMode = 1  # freecadcmd documents have undo off; the GUI's have it on
    yield document
    for name in set(FreeCAD.listDocuments()) - before:
        FreeCAD.closeDocument(name)


def sample_cloud(n=2000, seed=1, normals=False):
    rng = np.random.default_rng(seed)
    points = rng.uniform(-100, 100, (n, 3)) + [0.0, 0.0, 1200.0]  # a scanner ~1.2 m away
    normal = None
    if normals:
        normal = rng.normal(size=(n, 3))
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return Cloud(points, normal, name="sample")


def reopen(doc, path):
    doc.saveAs(str(path))
    name = doc.Name
    FreeCAD.closeDocument(name)
    return FreeCAD.openDocument(str(path))


def test_make_scan_round_trip_is_float32_exact(doc):
    cloud = sample_cloud(normals=True)
    obj = scan.make_scan(doc, cloud, name="my scan.ply", units="m", source="/data/my scan.ply")
    assert obj.TypeId == "Points::FeaturePython" and lookups.is_scan(obj)
    assert obj.Label == "my scan.ply" and obj.Units == "m" and obj.SourceFile == "/data/my scan.ply"
    assert obj.Points.CountPoints == obj.PointCount == len(cloud)
    back = scan.scan_cloud(obj)
    np.testing.assert_array_equal(back.points, cloud.points.astype(np.float32).astype(np.float64))
    assert np.abs(back.points - cloud.points).max() < 1e-4  # float32 at 1.3 m
    np.testing.assert_allclose(back.normals, cloud.normals, atol=1e-6)
    # The cache is not shared with callers: changing the copy leaves the scan as it was.
    back.points[:] = 0
    assert scan.scan_cloud(obj).points[0, 2] > 1000


def test_scan_cloud_survives_save_and_reopen(doc, tmp_path):
    cloud = sample_cloud()
    obj = scan.make_scan(doc, cloud)
    before, name = scan.scan_cloud(obj).points, obj.Name
    doc2 = reopen(doc, tmp_path / "scan.FCStd")
    again = doc2.getObject(name)
    assert lookups.is_scan(again)
    np.testing.assert_array_equal(scan.scan_cloud(again).points, before)


def test_scan_cloud_applies_placement_and_follows_point_changes(doc):
    obj = scan.make_scan(doc, sample_cloud(50))
    raw = scan.scan_cloud(obj).points
    obj.Placement = FreeCAD.Placement(FreeCAD.Vector(10, 20, 30), FreeCAD.Rotation(FreeCAD.Vector(0, 0, 1), 90))
    moved = scan.scan_cloud(obj).points
    expected = raw @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]).T + [10, 20, 30]
    np.testing.assert_allclose(moved, expected, atol=1e-3)
    obj.Placement = FreeCAD.Placement()
    obj.Points = Points.Points([(1, 2, 3)])
    np.testing.assert_array_equal(scan.scan_cloud(obj).points, [[1, 2, 3]])


def test_plain_points_and_mesh_objects_are_scans(doc):
    pts = doc.addObject("Points::Feature", "Plain")
    pts.Points = Points.Points([(0, 0, 0), (1, 0, 0), (0, 2, 0)])
    pts.Placement.Base = FreeCAD.Vector(5, 0, 0)
    np.testing.assert_allclose(scan.scan_cloud(pts).points, [[5, 0, 0], [6, 0, 0], [5, 2, 0]])
    mesh = doc.addObject("Mesh::Feature", "MeshScan")
    mesh.Mesh = Mesh.createBox(10, 20, 30)
    cloud = scan.scan_cloud(mesh)
    assert len(cloud) == mesh.Mesh.CountPoints == 8 and cloud.triangles is None
    np.testing.assert_allclose(cloud.points.max(axis=0) - cloud.points.min(axis=0), [10, 20, 30])
    scan.set_regions(pts, workpiece=[0, 2])
    assert scan.get_regions(pts)["workpiece"].tolist() == [0, 2]


def test_not_a_scan_is_an_input_error_naming_it(doc):
    box = doc.addObject("Part::Box", "Box")
    doc.recompute()
    with pytest.raises(InputError, match="'Box' is not a point cloud or mesh"):
        scan.scan_cloud(box)
    empty = doc.addObject("Points::Feature", "Empty")
    with pytest.raises(InputError, match="'Empty': contains no points"):
        scan.scan_cloud(empty)
    with pytest.raises(InputError, match="contains no points"):
        scan.make_scan(doc, Cloud(np.zeros((0, 3)), name="nothing"))
    assert [o.Name for o in doc.Objects] == ["Box", "Empty"]


def test_regions_round_trip_and_survive_reopen(doc, tmp_path):
    obj = scan.make_scan(doc, sample_cloud(1000))
    assert scan.get_regions(obj) == {"workpiece": None, "reference": None, "source": None}
    mask = np.zeros(1000, bool)
    mask[100:400] = True
    scan.set_regions(obj, workpiece=mask, reference=[999, 5, 5, 7], source="auto")
    regions = scan.get_regions(obj)
    assert regions["workpiece"].tolist() == list(range(100, 400))
    assert regions["reference"].tolist() == [5, 7, 999]
    assert regions["source"] == "auto" and scan.has_regions(obj)
    assert obj.Workpiece == 300 and obj.Reference == 3
    # As WorkCal 0.1 saved a scan: the counts and the source under longer names; reopening brings them up to date.
    obj.removeProperty("Source")
    obj.addProperty("App::PropertyEnumeration", "RegionSource", "Regions", "")
    obj.RegionSource = scan.REGION_SOURCES
    obj.RegionSource = "auto"
    obj.addProperty("App::PropertyInteger", "WorkpiecePoints", "Regions", "")
    name = obj.Name
    doc2 = reopen(doc, tmp_path / "regions.FCStd")
    assert {"RegionSource", "WorkpiecePoints"}.isdisjoint(doc2.getObject(name).PropertiesList)
    assert doc2.getObject(name).Workpiece == 300
    again = scan.get_regions(doc2.getObject(name))
    assert again["workpiece"].dtype.kind == "i"
    np.testing.assert_array_equal(again["workpiece"], regions["workpiece"])
    np.testing.assert_array_equal(again["reference"], regions["reference"])
    assert again["source"] == "auto"


def test_clearing_regions(doc):
    obj = scan.make_scan(doc, sample_cloud(100))
    scan.set_regions(obj, workpiece=[1, 2], reference=[3])
    scan.set_regions(obj)
    assert scan.get_regions(obj) == {"workpiece": None, "reference": None, "source": None}
    assert not scan.has_regions(obj)


@pytest.mark.parametrize("kwargs, message", [
    (dict(workpiece=[0, 100]), r"indices outside 0\.\.99"),
    (dict(workpiece=[-1]), "indices outside"),
    (dict(workpiece=[1, 2], reference=[2, 3]), "1 points are in both"),
    (dict(workpiece=np.ones(5, bool)), "mask has 5 entries"),
    (dict(workpiece=[0.5]), "integer point indices"),
    (dict(workpiece=[1], source="magic"), "'user' or 'auto'"),
])
def test_bad_regions_are_refused_and_change_nothing(doc, kwargs, message):
    obj = scan.make_scan(doc, sample_cloud(100))
    scan.set_regions(obj, workpiece=[10], reference=[20])
    with pytest.raises(InputError, match=message):
        scan.set_regions(obj, **kwargs)
    regions = scan.get_regions(obj)
    assert regions["workpiece"].tolist() == [10] and regions["reference"].tolist() == [20]


def test_stale_regions_are_reported(doc):
    obj = scan.make_scan(doc, sample_cloud(100))
    scan.set_regions(obj, workpiece=[99])
    obj.Points = Points.Points([(0, 0, 0)] * 3)
    with pytest.raises(InputError, match="no longer exist"):
        scan.get_regions(obj)


def test_undo_of_regions_restores_them(doc):
    obj = scan.make_scan(doc, sample_cloud(100))
    scan.set_regions(obj, workpiece=[1])
    doc.openTransaction("pick")
    scan.set_regions(obj, workpiece=[1, 2, 3], reference=[50])
    doc.abortTransaction()
    assert scan.get_regions(obj)["workpiece"].tolist() == [1] and scan.get_regions(obj)["reference"] is None


def test_import_scan_files_with_units(doc, tmp_path):
    cloud = sample_cloud(300)
    write_xyz(tmp_path / "s.xyz", Cloud(cloud.points / 1000.0), units="mm")  # numbers in metres
    obj = scan.import_scan(doc, tmp_path / "s.xyz", units="m")
    np.testing.assert_allclose(scan.scan_cloud(obj).points, cloud.points, atol=1e-3)
    assert obj.Units == "m" and obj.Label == "s.xyz" and obj.SourceFile.endswith("s.xyz")
    # A PLY written by WorkCal declares its unit; that wins over the unit asked for.
    write_ply(tmp_path / "s.ply", cloud, units="cm")  # the file holds cm numbers
    obj2 = scan.import_scan(doc, tmp_path / "s.ply", units="m")
    assert obj2.Units == "cm"
    np.testing.assert_allclose(scan.scan_cloud(obj2).points, cloud.points, atol=1e-3)


def test_import_scan_errors_leave_the_document_alone(doc, tmp_path):
    (tmp_path / "bad.xyz").write_text("1 2 three\n")
    with pytest.raises(InputError, match="bad.xyz"):
        scan.import_scan(doc, tmp_path / "bad.xyz")
    with pytest.raises(InputError, match="does not exist"):
        scan.import_scan(doc, tmp_path / "missing.e57")
    (tmp_path / "junk.e57").write_bytes(b"not an e57 file at all")
    with pytest.raises(InputError, match="junk.e57"):
        scan.import_scan(doc, tmp_path / "junk.e57")
    with pytest.raises(InputError, match="unknown length unit"):
        scan.import_scan(doc, tmp_path / "bad.xyz", units="furlong")
    assert doc.Objects == [] and FreeCAD.ActiveDocument is doc
    assert "WorkCalRead" not in FreeCAD.listDocuments()


def test_import_type_is_registered_and_inserts_a_scan(doc, tmp_path):
    assert "workcal_wb.fc.init" in FreeCAD.getImportType("e57")
    assert "workcal_wb.fc.init" in FreeCAD.getImportType("xyz")
    write_xyz(tmp_path / "f.xyz", sample_cloud(20))
    obj = fc_init.insert(str(tmp_path / "f.xyz"), doc.Name)
    assert lookups.is_scan(obj) and obj.Document is doc and obj.PointCount == 20


# --- models -------------------------------------------------------------------------------------

def test_model_cloud_of_a_part_box_is_its_surface(doc):
    box = doc.addObject("Part::Box", "Box")
    box.Length, box.Width, box.Height = 40, 20, 10
    box.Placement.Base = FreeCAD.Vector(100, 0, 0)
    doc.recompute()
    cloud = models.model_cloud(box)
    assert cloud.is_mesh and len(cloud.triangles) == 12 and cloud.name == "Box"
    np.testing.assert_allclose(cloud.points.min(axis=0), [100, 0, 0], atol=1e-9)
    np.testing.assert_allclose(cloud.points.max(axis=0), [140, 20, 10], atol=1e-9)
    corners = cloud.points[cloud.triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert area == pytest.approx(2 * (40 * 20 + 40 * 10 + 20 * 10))


def test_model_cloud_of_a_curved_part_follows_its_surface(doc):
    sphere = doc.addObject("Part::Sphere", "Ball")
    sphere.Radius = 50
    doc.recompute()
    cloud = models.model_cloud(sphere)
    radii = np.linalg.norm(cloud.points, axis=1)
    np.testing.assert_allclose(radii, 50, atol=1e-6)
    centres = cloud.points[cloud.triangles].mean(axis=1)
    assert 50 - np.linalg.norm(centres, axis=1).min() < 2 * models.deflection_for(sphere.Shape) + 0.05


def test_model_cloud_of_mesh_and_points(doc):
    mesh = doc.addObject("Mesh::Feature", "M")
    mesh.Mesh = Mesh.createBox(10, 10, 10)
    cloud = models.model_cloud(mesh)
    assert cloud.is_mesh and len(cloud.triangles) == 12 and len(cloud) == 8
    pts = doc.addObject("Points::Feature", "P")
    pts.Points = Points.Points([(0, 0, 0), (1, 1, 1)])
    cloud = models.model_cloud(pts)
    assert not cloud.is_mesh and cloud.points.tolist() == [[0, 0, 0], [1, 1, 1]]


def test_model_in_an_app_part_gets_the_container_placement(doc):
    part = doc.addObject("App::Part", "Container")
    part.Placement.Base = FreeCAD.Vector(0, 0, 500)
    mesh = doc.addObject("Mesh::Feature", "Inside")
    mesh.Mesh = Mesh.createBox(10, 10, 10)
    part.addObject(mesh)
    doc.recompute()
    assert models.model_cloud(mesh).points[:, 2].min() == pytest.approx(495)


def test_bad_models_are_input_errors_naming_the_object(doc):
    feature = doc.addObject("App::FeaturePython", "Notes")
    with pytest.raises(InputError, match=r"'Notes' \(App::FeaturePython\) is not a Part shape, mesh or point cloud"):
        models.model_cloud(feature)
    empty_mesh = doc.addObject("Mesh::Feature", "EmptyMesh")
    with pytest.raises(InputError, match="'EmptyMesh': the mesh has no faces"):
        models.model_cloud(empty_mesh)
    empty_points = doc.addObject("Points::Feature", "NoPoints")
    with pytest.raises(InputError, match="'NoPoints': the point cloud contains no points"):
        models.model_cloud(empty_points)
    line = doc.addObject("Part::Line", "Line")
    doc.recompute()
    with pytest.raises(InputError, match="'Line': its shape has no faces"):
        models.model_cloud(line)
    sheet = doc.addObject("Spreadsheet::Sheet", "Sheet")
    with pytest.raises(InputError, match="'Sheet'"):
        models.check_model(sheet)
    empty_shape = doc.addObject("Part::Feature", "Nothing")
    with pytest.raises(InputError, match="'Nothing': its shape is empty"):
        models.model_cloud(empty_shape)


def test_import_model_files(doc, tmp_path):
    box = Part.makeBox(30, 20, 10)
    box.exportStep(str(tmp_path / "box.step"))
    step = models.import_model_file(doc, tmp_path / "box.step", units="m")  # STEP carries its own unit
    assert step.TypeId == "Part::Feature" and step.Label == "box.step"
    assert step.Shape.BoundBox.XLength == pytest.approx(30)
    mesh = Mesh.Mesh(box.tessellate(0.1))
    mesh.write(str(tmp_path / "box.stl"))
    stl = models.import_model_file(doc, tmp_path / "box.stl", units="cm")
    assert stl.TypeId == "Mesh::Feature" and stl.Mesh.CountFacets == 12
    assert stl.Mesh.BoundBox.XLength == pytest.approx(300)
    write_xyz(tmp_path / "pts.xyz", sample_cloud(10))
    assert models.import_model_file(doc, tmp_path / "pts.xyz").TypeId == "Points::Feature"
    (tmp_path / "broken.step").write_text("ISO-10303-21; garbage")
    with pytest.raises(InputError, match="broken.step"):
        models.import_model_file(doc, tmp_path / "broken.step")
    with pytest.raises(InputError, match="unknown model file type"):
        models.import_model_file(doc, tmp_path / "x.docx")
    assert len(doc.Objects) == 3


# --- setup --------------------------------------------------------------------------------------

def test_setup_round_trip_and_reopen(doc, tmp_path):
    assert setup.get_setup(doc) == {"scan": None, "workpiece": None, "reference": None}
    s = scan.make_scan(doc, sample_cloud(50), name="S")
    wp = doc.addObject("Part::Box", "Workpiece")
    ref = doc.addObject("Mesh::Feature", "Reference")
    ref.Mesh = Mesh.createSphere(10)
    doc.recompute()
    obj = setup.set_setup(doc, scan=s, workpiece=wp)
    assert obj.Name == setup.SETUP_NAME
    setup.set_setup(doc, reference=ref)  # the others stay
    assert setup.get_setup(doc) == {"scan": s, "workpiece": wp, "reference": ref}
    doc2 = reopen(doc, tmp_path / "setup.FCStd")
    chosen = setup.get_setup(doc2)
    assert [chosen[r].Name for r in setup.ROLES] == ["S", "Workpiece", "Reference"]
    setup.set_setup(doc2, reference=None)
    assert setup.get_setup(doc2)["reference"] is None
    assert len([o for o in doc2.Objects if o.Name.startswith(setup.SETUP_NAME)]) == 1


def test_setup_refuses_bad_choices_and_changes_nothing(doc):
    s = scan.make_scan(doc, sample_cloud(50), name="S")
    box = doc.addObject("Part::Box", "Box")
    sheet = doc.addObject("Spreadsheet::Sheet", "Sheet")
    doc.recompute()
    setup.set_setup(doc, scan=s, workpiece=box)
    with pytest.raises(InputError, match="'Sheet'"):
        setup.set_setup(doc, reference=sheet)
    with pytest.raises(InputError, match="both the workpiece and the reference"):
        setup.set_setup(doc, reference=box)
    with pytest.raises(InputError, match="'S' is the scan"):
        setup.set_setup(doc, reference=s)
    with pytest.raises(InputError, match="'Box' is not a point cloud or mesh"):
        setup.set_setup(doc, scan=box)
    assert setup.get_setup(doc) == {"scan": s, "workpiece": box, "reference": None}


def test_setup_link_is_cleared_when_the_model_is_deleted(doc):
    box = doc.addObject("Part::Box", "Box")
    doc.recompute()
    setup.set_setup(doc, workpiece=box)
    doc.removeObject("Box")
    assert setup.get_setup(doc)["workpiece"] is None


def test_a_scan_and_a_model_read_again_in_another_unit_are_one_undo_step_each(doc, tmp_path):
    points_m = np.random.default_rng(3).uniform(0.0, 0.3, size=(500, 3))
    path = tmp_path / "in_metres.xyz"
    np.savetxt(path, points_m, fmt="%.6f")
    obj = scan.import_scan(doc, path, "mm")
    text, suggestion = scan.scan_unit_warning(obj)
    assert "in_metres.xyz" in text and "read it with unit m" in text and suggestion == "m"
    scan.change_units(obj, "m")
    assert obj.Units == "m" and scan.scan_unit_warning(obj) == ("", None)
    np.testing.assert_allclose(scan.scan_cloud(obj).points, points_m * 1000.0, atol=1e-3)
    assert doc.UndoNames[0] == "Scan unit"
    doc.undo()
    assert obj.Units == "mm"
    np.testing.assert_allclose(scan.scan_cloud(obj).points, points_m, atol=1e-6)

    model = models.import_model(doc, path, "mm")
    assert models.file_units(model) == "mm" and models.model_unit_warning(model)[1] == "m"
    models.change_units(model, "m")
    assert models.file_units(model) == "m" and models.model_unit_warning(model) == ("", None)
    assert doc.UndoNames[0] == "Model unit"


def test_a_scan_not_read_from_a_file_cannot_change_its_unit(doc):
    obj = scan.make_scan(doc, sample_cloud(), "Made")
    with pytest.raises(InputError, match="'Made' was not read from a file"):
        scan.change_units(obj, "m")
    with pytest.raises(InputError, match="unknown length unit"):
        scan.change_units(obj, "furlong")


def test_the_same_model_for_both_roles_is_refused_naming_both(doc, tmp_path):
    path = tmp_path / "bracket.step"
    Part.makeBox(60, 40, 20).exportStep(str(path))
    first = models.import_model(doc, path)
    second = models.import_model(doc, path)
    setup.choose_models(doc, workpiece=first)
    with pytest.raises(InputError, match=r"'bracket.step001' cannot be the reference model: it is the workpiece "
                                         r"model 'bracket.step' again \(read from the same file bracket.step\)"):
        setup.check_setup(doc, reference=second)
    copy = doc.addObject("Part::Feature", "Copy")
    copy.Shape = first.Shape.copy()
    with pytest.raises(InputError, match="the same shape at the same place"):
        setup.check_setup(doc, reference=copy)
    other = doc.addObject("Part::Feature", "Cube")
    other.Shape = Part.makeBox(60, 40, 20, FreeCAD.Vector(300, 0, 0))  # the same size elsewhere: another object
    assert setup.check_setup(doc, reference=other)["reference"] is other
