"""Headless tests of the Subd2Nurbs workbench (label freecad), run inside freecadcmd by
run_workbench_tests.py. Environment: S2N_CLI (the subd2nurbs executable), S2N_CORPUS (the
OpenSubdiv corpus); sys.path holds build/python and freecad_plugin.

Oracles: face counts from the cage file itself (one face per quad; one per face corner when
the cage has n-gons or triangles), FreeCAD's own checks (isValid, isClosed), OCCT's
measurement of the CLI's STEP file read by FreeCAD (faces, area), the document's object
list before and after a failure."""

import os
import shutil
import subprocess
import tempfile
import unittest

import FreeCAD as App
import Mesh
import Part

import subd2nurbs
import s2n_freecad.api as s2n
from s2n_freecad import features

CORPUS = os.environ.get("S2N_CORPUS", "")
CLI = os.environ.get("S2N_CLI", "")
SAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples")


def corpus(name):
    return os.path.join(CORPUS, name + ".obj")


def face_sizes(path):
    return [len(line.split()) - 1 for line in open(path) if line.startswith("f ")]


def expected_faces(path):
    """One B-rep face per quad of an all-quad cage, else one per face corner (one
    Catmull-Clark step makes the cage all quads)."""
    sizes = face_sizes(path)
    return len(sizes) if all(n == 4 for n in sizes) else sum(sizes)


def first_face_poles(shape):
    s = shape.Faces[0].Surface
    return s.NbUPoles * s.NbVPoles


class Workbench(unittest.TestCase):
    def setUp(self):
        self.doc = App.newDocument("s2n_test")
        self.tmp = tempfile.mkdtemp(prefix="s2n_fc_")

    def tearDown(self):
        App.closeDocument(self.doc.Name)
        shutil.rmtree(self.tmp, ignore_errors=True)

    def names(self):
        return sorted(o.Name for o in self.doc.Objects)

    def assertSolid(self, shape, faces):
        self.assertTrue(shape.isValid())
        self.assertEqual(len(shape.Solids), 1)
        self.assertTrue(shape.Solids[0].isClosed())
        self.assertEqual(len(shape.Faces), faces)
        self.assertGreater(shape.Volume, 0)

    def test_import_and_convert_corpus_cages(self):
        for name in ("catmark_cube_creases0", "catmark_pyramid_creases0", "catmark_torus_creases0"):
            with self.subTest(name):
                path = corpus(name)
                cage = s2n.make_cage(path, doc=self.doc)
                self.assertEqual(cage.NumFaces, len(face_sizes(path)))
                self.assertEqual(cage.NumVertices, sum(1 for line in open(path) if line.startswith("v ")))
                info = subd2nurbs.info(subd2nurbs.read_cage(path))
                self.assertEqual(len(cage.Shape.Edges), info["edges"])  # the cage as wires
                nurbs = s2n.make_nurbs(cage, progress=False, faces="PerQuad")
                self.assertSolid(nurbs.Shape, expected_faces(path))
                self.assertEqual(nurbs.Patches, expected_faces(path))
                self.assertEqual(nurbs.RecoveredQuads, -1)
                self.assertLess(nurbs.MaxGap, 1e-9 * info["bounds"]["diagonal"])

    def test_creases_survive_import(self):
        path = corpus("catmark_cube_creases0")
        cage = s2n.make_cage(path, doc=self.doc)
        self.assertEqual(cage.NumCreases, len(subd2nurbs.read_cage(path).creases))
        self.assertGreater(cage.NumCreases, 0)

    def test_properties_and_source_changes_recompute(self):
        cage = s2n.make_cage(corpus("catmark_cube"), doc=self.doc)
        nurbs = s2n.make_nurbs(cage, progress=False)
        area0 = nurbs.Shape.Area
        nurbs.Level = 1
        self.doc.recompute()
        self.assertSolid(nurbs.Shape, 6)
        poles1 = first_face_poles(nurbs.Shape)
        nurbs.Level = 2
        self.doc.recompute()
        # One face per cage quad at every level; each level adds knots towards the corners.
        self.assertSolid(nurbs.Shape, 6)
        self.assertGreater(first_face_poles(nurbs.Shape), poles1)
        # Moving a cage vertex recomputes the NURBS object through the link.
        coords = list(cage.Coordinates)
        coords[0] -= 0.5
        cage.Coordinates = coords
        self.doc.recompute()
        self.assertSolid(nurbs.Shape, 6)
        self.assertNotAlmostEqual(nurbs.Shape.Area, area0, places=6)
        # A different source gives its face count (packed faces: the module's count).
        other = s2n.make_cage(corpus("catmark_pyramid_creases0"), doc=self.doc)
        nurbs.Source = other
        self.doc.recompute()
        packed = subd2nurbs.convert(subd2nurbs.read_cage(corpus("catmark_pyramid_creases0"))).brep["faces"]
        self.assertLess(packed, expected_faces(corpus("catmark_pyramid_creases0")))
        self.assertSolid(nurbs.Shape, packed)
        nurbs.OutputType = "Shell"
        self.doc.recompute()
        self.assertEqual(nurbs.Shape.ShapeType, "Shell")
        self.assertTrue(nurbs.Shape.isClosed())

    def test_save_reopen_recompute(self):
        cage = s2n.make_cage(corpus("catmark_cube_creases1"), doc=self.doc)
        nurbs = s2n.make_nurbs(cage, level=1, progress=False)
        faces, area = len(nurbs.Shape.Faces), nurbs.Shape.Area
        nurbs_name, cage_name = nurbs.Name, cage.Name
        path = os.path.join(self.tmp, "saved.FCStd")
        self.doc.saveAs(path)
        App.closeDocument(self.doc.Name)
        self.doc = App.openDocument(path)
        nurbs = self.doc.getObject(nurbs_name)
        cage = self.doc.getObject(cage_name)
        self.assertIsInstance(nurbs.Proxy, features.NurbsFeature)
        self.assertIsInstance(cage.Proxy, features.CageFeature)
        self.assertEqual(nurbs.Level, 1)
        self.assertIs(nurbs.Source, cage)
        cage.touch()
        self.doc.recompute()
        self.assertSolid(nurbs.Shape, faces)
        self.assertAlmostEqual(nurbs.Shape.Area, area, delta=1e-9 * area)
        report = s2n.check_quality(nurbs)  # the result is rebuilt after a reload
        self.assertEqual(report["faces"], faces)

    def test_bad_cage_leaves_the_document_unchanged(self):
        s2n.make_cage(corpus("catmark_cube"), doc=self.doc)
        before = self.names()
        bad = os.path.join(self.tmp, "nonmanifold.obj")
        with open(bad, "w") as f:  # edge 1-2 shared by three faces
            f.write("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 1\nv 2 1 0\n"
                    "f 1 2 3 4\nf 2 5 3\nf 2 3 6\n")
        with self.assertRaises(subd2nurbs.CageError) as cm:
            s2n.make_cage(bad, doc=self.doc)
        self.assertIn("nonmanifold.obj", str(cm.exception))
        self.assertEqual(self.names(), before)
        # A non-manifold triangle mesh is refused by make_nurbs, again without a trace.
        mesh = self.doc.addObject("Mesh::Feature", "BadMesh")
        mesh.Mesh = Mesh.Mesh([[(0, 0, 0), (1, 0, 0), (1, 1, 0)], [(1, 0, 0), (0, 0, 0), (0, 0, 1)],
                               [(0, 0, 0), (1, 0, 0), (0, -1, 0)]])
        self.doc.recompute()
        before = self.names()
        with self.assertRaises(Exception):
            s2n.make_nurbs(mesh, progress=False)
        self.assertEqual(self.names(), before)
        # Settings errors too.
        cage = self.doc.getObject(before[0]) if features.is_cage(self.doc.getObject(before[0])) else \
            [o for o in self.doc.Objects if features.is_cage(o)][0]
        with self.assertRaises(ValueError):
            s2n.make_nurbs(cage, level=-1, progress=False)
        with self.assertRaises(ValueError):
            s2n.make_nurbs(cage, polar="Sometimes", progress=False)
        self.assertEqual(self.names(), before)

    def test_failed_recompute_keeps_the_last_shape(self):
        cage = s2n.make_cage(corpus("catmark_cube"), doc=self.doc)
        nurbs = s2n.make_nurbs(cage, progress=False)
        area = nurbs.Shape.Area
        nurbs.Level = -1  # refused by the converter
        self.doc.recompute()
        self.assertFalse(nurbs.isValid())
        self.assertAlmostEqual(nurbs.Shape.Area, area, delta=1e-12 * area)
        nurbs.Level = 0
        self.doc.recompute()
        self.assertTrue(nurbs.isValid())

    def test_settings_rules_are_the_converters_in_every_front_end(self):
        """Each setting's rule lives in the converter (issue #15): the CLI (exit 1), the Python
        module (SettingsError.setting / .rule) and the workbench show the same rule text, each
        after its own name for the setting. The Python module's error carries the converter's
        text (raised in C++); the CLI and the workbench are compared with it."""
        path = corpus("catmark_cube")
        cage = subd2nurbs.read_cage(path)
        glb = os.path.join(self.tmp, "p.glb")
        fair_rule = "must be a positive number (the weight of the fairing energy)"
        # (Python keyword arguments, CLI options, the workbench's properties or None, setting, rule)
        cases = [
            ({"level": -1}, ["--level=-1"], {"Level": -1}, "level", "must be 0 .. 12"),
            ({"level": 13}, ["--level", "13"], {"Level": 13}, "level", "must be 0 .. 12"),
            ({"tolerance": 0.0}, ["--tolerance", "0"], None, "tolerance", "must be a positive number"),
            ({"level": 1, "tolerance": 0.1}, ["--level", "1", "--tolerance", "0.1"], None, "tolerance",
             "excludes a level (the tolerance chooses the levels)"),
            ({"absolute": True}, ["--absolute"], None, "absolute", "needs a tolerance"),
            ({"radial_steps": 3}, ["--radial-steps", "3"], None, "radial_steps", "must be 1 or 2"),
            ({"radial_steps": 0}, ["--radial-steps", "0"], None, "radial_steps", "must be 1 or 2"),
            ({"polar_lambda": 0}, ["--lambda", "0"], None, "polar_lambda", "must be a positive number"),
            ({"polar": False, "separate_poles": True}, ["--polar", "off", "--separate-poles"], None,
             "separate_poles", "needs polar caps"),
            ({"fit": "interpolate", "separate_poles": True}, ["--fit", "interpolate", "--separate-poles"], None,
             "separate_poles", "is not supported by the interpolating fit (the separating step changes the "
             "subdivision rule the fit solves for)"),
            ({"fair": 1.0}, ["--fair", "1"], {"FairWeight": 1.0}, "fair", "needs the interpolating fit"),
            ({"fit": "interpolate", "fair": -2.0}, ["--fit", "interpolate", "--fair=-2"],
             {"Fit": "Interpolate", "FairWeight": -2.0}, "fair", fair_rule),
            ({"fit": "exact"}, ["--fit", "exact"], {"Fit": "exact"}, "fit", "must be approximate or interpolate"),
            ({"faces": "all"}, ["--faces", "all"], {"Faces": "all"}, "faces", "must be packed or per-quad"),
            ({"max_faces": 0}, ["--max-faces", "0"], {"MaxFaces": -1.0}, "max_faces", "must be a positive number"),
            ({"max_memory": -1}, None, {"MaxMemoryMiB": -1.0}, "max_memory", "must be a positive number"),
            ({"threads": 0}, ["--threads", "0"], {"Threads": -1}, "threads", "must be 1 .. 1024"),
            ({"max_memory": "12Q"}, ["--max-memory", "12Q"], None, "max_memory",
             "'12Q' is not a size (bytes, or a number with K, M, G or T, e.g. 8G)"),
            ({"preview": "curvature", "preview_samples": 1}, ["--preview", glb, "--preview-samples", "1"],
             {"Samples": 1}, "preview_samples", "must be 2 .. 64"),
            ({"preview": "rainbow"}, ["--preview", glb, "--color", "rainbow"], None, "preview",
             "must be deviation, curvature or zebra"),
            # Polar mode: the command line's names are the converter's; the workbench maps its
            # PolarHandling choices onto them, and a value outside its choices meets the rule.
            ({"polar": "sometimes"}, ["--polar", "sometimes"], {"PolarHandling": "sometimes"}, "polar",
             "must be on or off"),
        ]
        cli_name = {"polar_lambda": "--lambda", "preview": "--color"}
        nurbs = s2n.make_nurbs(s2n.make_cage(path, doc=self.doc), progress=False)
        color_map = s2n.make_color_map(nurbs, samples=3)
        for kwargs, options, properties, setting, rule in cases:
            with self.subTest(setting=setting, kwargs=kwargs):
                with self.assertRaises(subd2nurbs.SettingsError) as e:
                    subd2nurbs.convert(cage, brep=False, **kwargs)
                self.assertEqual((e.exception.setting, e.exception.rule), (setting, rule))
                self.assertEqual(str(e.exception), "%s %s" % (setting, rule))
                converters = e.exception.rule
                if options is not None:
                    r = subprocess.run([CLI, "convert", path, "-o", os.path.join(self.tmp, "o.step")] + options,
                                       capture_output=True, text=True)
                    self.assertEqual(r.returncode, 1, r.stderr)
                    flag = cli_name.get(setting, "--" + setting.replace("_", "-"))
                    self.assertEqual(r.stderr, "subd2nurbs: error: %s %s\n" % (flag, converters))
                if properties is not None:
                    obj = color_map if "Samples" in properties else nurbs
                    self.assert_property_rule(obj, properties, setting, converters)
        # The cage's subdivision options: the Python module's Cage and the workbench's Cage
        # object (its Boundary, CreaseMethod, TriangleRule); the command line reads them from
        # OBJ tags, in OpenSubdiv's own words (docs/formats.md).
        cage_object = nurbs.Source
        for setting, prop in (("boundary", "Boundary"), ("crease_method", "CreaseMethod"),
                              ("triangles", "TriangleRule")):
            with self.subTest(setting=setting):
                self.assertEqual(features.PROPERTY_OF_SETTING[setting], prop)
                # The workbench offers the converter's names, no others.
                self.assertEqual(sorted(cage_object.getEnumerationsOfProperty(prop)),
                                 sorted(subd2nurbs.CAGE_OPTIONS[setting]))
                with self.assertRaises(subd2nurbs.SettingsError) as e:
                    subd2nurbs.Cage(cage.vertices, cage.faces, **{setting: "sometimes"})
                self.assertEqual(e.exception.setting, setting)
                self.assertEqual(str(e.exception), "%s %s" % (setting, e.exception.rule))
                # A choice the converter does not know (a document from another version): the
                # Cage object and the NURBS object made from it fail with the converter's rule.
                choices = cage_object.getEnumerationsOfProperty(prop)
                current = getattr(cage_object, prop)
                setattr(cage_object, prop, choices + ["sometimes"])
                setattr(cage_object, prop, "sometimes")
                self.doc.recompute()
                self.assertFalse(cage_object.isValid())
                self.assertIn("%s %s" % (prop, e.exception.rule), cage_object.getStatusString())
                with self.assertRaises(subd2nurbs.SettingsError) as shown:  # the NURBS object's conversion
                    nurbs.Proxy.result(nurbs)
                self.assertEqual(str(shown.exception), "%s %s" % (prop, e.exception.rule))
                setattr(cage_object, prop, choices)
                setattr(cage_object, prop, current)
                self.doc.recompute()
                self.assertTrue(cage_object.isValid())
                self.assertTrue(nurbs.isValid())
        with self.assertRaises(subd2nurbs.SettingsError) as e:  # before the document is touched
            s2n.make_nurbs(nurbs.Source, level=13, progress=False)
        self.assertEqual(str(e.exception), "Level must be 0 .. 12")
        with self.assertRaises(RuntimeError) as e:  # converted on recompute: the message says why
            s2n.make_color_map(nurbs, samples=65)
        self.assertIn("Samples must be 2 .. 64", str(e.exception))
        # The Python module's own type checks keep their SettingsError, naming the setting.
        for kwargs in ({"level": 1.5}, {"radial_steps": True}, {"tolerance": "small"}):
            with self.assertRaises(subd2nurbs.SettingsError) as e:
                subd2nurbs.convert(cage, brep=False, **kwargs)
            self.assertEqual(e.exception.setting, next(iter(kwargs)))

    def assert_property_rule(self, obj, properties, setting, rule):
        """Sets `properties` on `obj` (an enumeration first given the value as a choice): the
        recompute fails with the converter's `rule` after the property's name; restored, it
        succeeds again."""
        saved = {name: (getattr(obj, name), obj.getEnumerationsOfProperty(name)) for name in properties}
        for name, value in properties.items():
            choices = saved[name][1]
            if choices is not None and value not in choices:
                setattr(obj, name, choices + [value])
            setattr(obj, name, value)
        self.doc.recompute()
        self.assertFalse(obj.isValid())
        self.assertIn("%s %s" % (features.PROPERTY_OF_SETTING[setting], rule), obj.getStatusString())
        for name, (value, choices) in saved.items():
            if choices is not None:
                setattr(obj, name, choices)
            setattr(obj, name, value)
        self.doc.recompute()
        self.assertTrue(obj.isValid())

    def test_settings_properties_come_from_the_table(self):
        """The NURBS object's conversion properties are the settings table's (subd2nurbs.SETTINGS):
        each row with a property is one, with its group and tooltip; a row added to the table is
        a property too, read back into convert()'s keywords, with no other edit."""
        cage = s2n.make_cage(corpus("catmark_cube"), doc=self.doc)
        nurbs = s2n.make_nurbs(cage, progress=False)
        rows = [row for row in subd2nurbs.SETTINGS if row["property"]]
        self.assertGreaterEqual(len(rows), 8)
        for row in rows:
            p = row["property"]
            with self.subTest(setting=row["name"]):
                self.assertIn(p["name"], nurbs.PropertiesList)
                self.assertEqual(nurbs.getGroupOfProperty(p["name"]), p["group"])
                self.assertEqual(nurbs.getDocumentationOfProperty(p["name"]), p["tooltip"])
                self.assertEqual(features.PROPERTY_OF_SETTING[row["name"]], p["name"])
        # Defaults: nothing given, so the converter's defaults apply.
        self.assertEqual(features.object_settings(nurbs), {"polar": "on", "fit": "approximate", "faces": "packed",
                                                           "planar_faces": "merge", "input": "auto",
                                                           "aim_at_target": False, "exact_spacing": False,
                                                           "fit_tolerance": 0.001, "feature_angle": 30.0})
        dummy = {"name": "dummy_setting", "type": "number", "default": None, "default_text": "", "help": "a test row",
                 "choices": [], "cli": None, "python": True,
                 "property": {"name": "DummySetting", "group": "Conversion", "tooltip": "only this test has it",
                              "choices": [], "zero_is_default": True, "scale": 1024.0}}
        saved = features.SETTING_ROWS
        try:
            features.SETTING_ROWS = saved + (dummy,)
            features.add_setting_properties(nurbs)
            self.assertIn("DummySetting", nurbs.PropertiesList)
            self.assertEqual(nurbs.getDocumentationOfProperty("DummySetting"), "only this test has it")
            self.assertNotIn("dummy_setting", features.object_settings(nurbs))  # 0: the default
            nurbs.DummySetting = 2.5
            self.assertEqual(features.object_settings(nurbs)["dummy_setting"], 2.5 * 1024.0)
        finally:
            features.SETTING_ROWS = saved
        # Level is ignored once Tolerance is given (the properties' documented meaning).
        self.assertEqual(features.settings_of({"Level": 2, "Tolerance": 1e-3}), {"tolerance": 1e-3})
        self.assertEqual(features.settings_of({"Level": 2, "Tolerance": 0.0, "MaxMemoryMiB": 2.0}),
                         {"level": 2, "max_memory": 2.0 * 1024 * 1024})

    def test_fitted_cage_follows_the_mesh_and_refits(self):
        """Fit cage to mesh: a perturbed torus cage fitted to a mesh of the true cage's refined
        surface comes closer to it (the fit's own two-sided measure, and FreeCAD's distance of the
        NURBS solid to the mesh's points); moving the mesh refits; a bad target leaves the
        document unchanged."""
        import numpy as np
        path = corpus("catmark_torus_creases0")
        truth = subd2nurbs.read_cage(path)
        fine = subd2nurbs.refine(truth, 3)
        tris = [[f[0], f[k], f[k + 1]] for f in fine.faces for k in (1, 2)]
        mesh_obj = self.doc.addObject("Mesh::Feature", "Scan")
        mesh_obj.Mesh = Mesh.Mesh([[list(fine.vertices[i]) for i in t] for t in tris])
        rng = np.random.default_rng(2)
        diag = np.linalg.norm(truth.vertices.max(0) - truth.vertices.min(0))
        moved = subd2nurbs.Cage(truth.vertices + rng.uniform(-0.02, 0.02, truth.vertices.shape) * diag,
                                truth.faces, truth.creases, truth.corners)
        cage = s2n.make_cage(moved, doc=self.doc)
        self.doc.recompute()
        fitted = s2n.make_fitted_cage(cage, mesh_obj, max_iterations=10)
        self.assertTrue(features.is_cage(fitted))
        self.assertGreater(fitted.Iterations, 0)
        self.assertLess(fitted.DistanceAfter, 0.3 * fitted.DistanceBefore)
        self.assertEqual(fitted.NumFaces, cage.NumFaces)
        self.assertEqual(fitted.NumCreases, cage.NumCreases)
        nurbs = s2n.make_nurbs(fitted, progress=False)
        self.assertTrue(nurbs.Shape.isValid())
        # FreeCAD's own measure: the mesh's points are closer to the fitted solid than to the
        # solid of the perturbed cage.
        plain = s2n.make_nurbs(cage, progress=False)
        probe = [App.Vector(*fine.vertices[i]) for i in range(0, len(fine.vertices), 37)]
        far = lambda shape: max(shape.distToShape(Part.Vertex(p))[0] for p in probe)
        self.assertLess(far(nurbs.Shape), 0.5 * far(plain.Shape))
        # Cancelled (the progress indicator's cancel, simulated after one iteration): the fit
        # stops after its first solve, says so, and keeps that solve's cage.
        features._FitProgress.cancel_after = 1
        try:
            stopped = s2n.make_fitted_cage(cage, mesh_obj, max_iterations=10)
        finally:
            features._FitProgress.cancel_after = None
        self.assertEqual(stopped.Stop, "cancelled")
        self.assertEqual(stopped.Iterations, 1)
        points, triangles = features.FittedCageFeature.target_arrays(mesh_obj)
        one, _ = subd2nurbs.fit(features.cage_of(cage), points, triangles=triangles, max_iterations=1)
        np.testing.assert_allclose(np.array(stopped.Coordinates), one.vertices.reshape(-1), rtol=1e-12, atol=0)
        # The target moves: the fitted cage follows (refit on recompute).
        before = list(fitted.Coordinates)
        mesh_obj.Placement = App.Placement(App.Vector(0.01 * diag, 0, 0), App.Rotation())
        self.doc.recompute()
        self.assertNotEqual(list(fitted.Coordinates), before)
        # A target without vertices: an error, the document unchanged.
        names = sorted(o.Name for o in self.doc.Objects)
        empty = self.doc.addObject("Part::Feature", "Empty")
        names.append(empty.Name)
        with self.assertRaises(Exception):
            s2n.make_fitted_cage(cage, empty)
        self.assertEqual(sorted(o.Name for o in self.doc.Objects), sorted(names))

    def test_packed_faces_are_the_same_solid(self):
        """Faces = Packed (the default) merges regular regions into one face each: fewer faces,
        the same solid as PerQuad (FreeCAD's own area and volume)."""
        for name, most in (("catmark_torus", 1), ("catmark_torus_creases0", 31)):
            with self.subTest(name):
                cage = s2n.make_cage(corpus(name), doc=self.doc)
                nurbs = s2n.make_nurbs(cage, progress=False)
                self.assertEqual(nurbs.Faces, "Packed")
                packed = nurbs.Shape.copy()
                self.assertTrue(packed.isValid())
                self.assertEqual(len(packed.Solids), 1)
                self.assertTrue(packed.Solids[0].isClosed())
                self.assertLessEqual(len(packed.Faces), most)
                self.assertEqual(nurbs.Patches, len(packed.Faces))
                nurbs.Faces = "PerQuad"
                self.doc.recompute()
                self.assertSolid(nurbs.Shape, expected_faces(corpus(name)))
                # FreeCAD's Area and Volume (OCCT's GProp) use a fixed number of points per face:
                # on one face over 32 spans it is off by 1.3e-5 (measured); check_step_import.py
                # checks 1e-9 with exact quadrature of the faces FreeCAD read.
                self.assertLess(abs(packed.Volume - nurbs.Shape.Volume), 1e-4 * nurbs.Shape.Volume)
                self.assertLess(abs(packed.Area - nurbs.Shape.Area), 1e-4 * nurbs.Shape.Area)

    def test_triangulated_mesh_feature_gives_the_cage_faces(self):
        for name, closed in (("catmark_cube", True), ("catmark_torus", True), ("catmark_helmet", False)):
            with self.subTest(name):
                path = corpus(name)
                mesh = self.doc.addObject("Mesh::Feature", name + "_mesh")
                mesh.Mesh = Mesh.read(path)  # FreeCAD's reader: triangles
                self.assertEqual(mesh.Mesh.CountFacets, 2 * len(face_sizes(path)))
                self.doc.recompute()
                nurbs = s2n.make_nurbs(mesh, progress=False, faces="PerQuad")
                self.assertEqual(nurbs.RecoveredQuads, len(face_sizes(path)))
                self.assertEqual(nurbs.KeptTriangles, 0)
                if closed:
                    self.assertSolid(nurbs.Shape, expected_faces(path))
                else:  # an open surface: a shell with the cage's face count
                    self.assertTrue(nurbs.Shape.isValid())
                    self.assertEqual(len(nurbs.Shape.Solids), 0)
                    self.assertEqual(len(nurbs.Shape.Faces), expected_faces(path))

    def test_mesh_feature_of_a_part_becomes_a_light_solid(self):
        # The mesh path (docs/meshes.md): a triangle STL of a part is remeshed, not taken as its own
        # cage. Oracle: the mesh's own volume (FreeCAD's Mesh.Volume) and its triangle count.
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "mesh", "plate_holes.STL")
        mesh = self.doc.addObject("Mesh::Feature", "plate")
        mesh.Mesh = Mesh.read(path)
        self.doc.recompute()
        nurbs = s2n.make_nurbs(mesh, progress=False, target_faces=300)
        self.assertTrue(nurbs.InputRoute.startswith("mesh: "), nurbs.InputRoute)
        self.assertGreater(nurbs.CageFaces, 0)
        # Lighter than FreeCAD's own Part from Mesh (one planar face per triangle).
        self.assertLess(len(nurbs.Shape.Faces), mesh.Mesh.CountFacets)
        self.assertTrue(nurbs.Shape.isValid())
        self.assertEqual(len(nurbs.Shape.Solids), 1)
        self.assertAlmostEqual(nurbs.Shape.Volume / mesh.Mesh.Volume, 1.0, delta=0.02)
        self.assertEqual(nurbs.TargetFaces, 300)

    def plate_mesh(self):
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "mesh", "plate_holes.STL")
        mesh = self.doc.addObject("Mesh::Feature", "plate")
        mesh.Mesh = Mesh.read(path)
        self.doc.recompute()
        return mesh

    def counting_conversions(self):
        """Counts features.convert_cage's calls (restored at the test's end)."""
        calls = []
        original = features.convert_cage

        def counted(*args, **kwargs):
            calls.append(1)
            return original(*args, **kwargs)
        features.convert_cage = counted
        self.addCleanup(setattr, features, "convert_cage", original)
        return calls

    def test_mesh_panel_previews_the_cage_and_ok_adds_that_conversion(self):
        # The mesh task panel's logic (mesh_panel.MeshConversion): the preview's cage and face
        # count are those of the NURBS object OK adds (FreeCAD's count of the solid read back),
        # without converting again; the cage kept on request is that NURBS object's cage.
        from s2n_freecad import mesh_panel
        mesh = self.plate_mesh()
        before = self.names()
        calls = self.counting_conversions()
        panel = mesh_panel.MeshConversion(mesh)
        self.assertEqual(panel.values["FitTolerance"], 1e-3)  # the settings table's defaults
        self.assertEqual(panel.values["TargetFaces"], 0)
        panel.values["TargetFaces"] = 200
        lines = panel.preview(progress=False)
        cage = panel.cage_object
        self.assertEqual(self.names(), sorted(before + [cage.Name]))
        self.assertTrue(all(n == 4 for n in cage.FaceSizes))
        nurbs = panel.accept(keep_cage=True, progress=False)
        self.assertEqual(len(calls), 1)  # OK reused the preview's conversion
        self.assertEqual(self.names(), sorted(before + [cage.Name, nurbs.Name]))
        self.assertSolid(nurbs.Shape, len(nurbs.Shape.Faces))
        self.assertEqual(nurbs.CageFaces, cage.NumFaces)
        self.assertEqual(nurbs.TargetFaces, 200)
        self.assertIn("Cage: %d quads" % cage.NumFaces, lines[0])
        self.assertTrue(any(line.startswith("NURBS: %d faces" % len(nurbs.Shape.Faces)) for line in lines), lines)
        # The kept cage converts (as a Cage) to the same solid: the same faces and volume.
        again = s2n.make_nurbs(cage, progress=False)
        self.assertEqual(len(again.Shape.Faces), len(nurbs.Shape.Faces))
        self.assertAlmostEqual(again.Shape.Volume, nurbs.Shape.Volume, delta=1e-9 * abs(nurbs.Shape.Volume))

    def test_mesh_panel_cancel_and_changed_settings_leave_the_document_right(self):
        from s2n_freecad import mesh_panel
        mesh = self.plate_mesh()
        before = self.names()
        calls = self.counting_conversions()
        panel = mesh_panel.MeshConversion(mesh)
        panel.values["TargetFaces"] = 200
        # A cancel inside the remesh (the progress callable returning False): nothing added.
        with self.assertRaises(subd2nurbs.Cancelled):
            panel.preview(progress=lambda stage, fraction: False if fraction > 0.2 else None)
        self.assertEqual(self.names(), before)
        # Cancel after a preview: the document as it was.
        panel.preview(progress=False)
        self.assertNotEqual(self.names(), before)
        panel.reject()
        self.assertEqual(self.names(), before)
        # Settings changed after the preview: OK converts again with them, and the previewed
        # cage (not this conversion's) is not kept.
        panel.preview(progress=False)
        previewed = panel.cage_object.Name
        panel.values["TargetFaces"] = 150
        nurbs = panel.accept(keep_cage=True, progress=False)
        self.assertEqual(len(calls), 4)
        self.assertEqual(nurbs.TargetFaces, 150)
        self.assertEqual(self.names(), sorted(before + [nurbs.Name]))
        self.assertNotIn(previewed, self.names())
        self.assertTrue(nurbs.Shape.isValid())

    def test_fit_interpolate_passes_through_the_cage_vertices(self):
        """The NURBS object's Fit property: Interpolate makes the shape pass through the cage's
        vertices (FreeCAD's own distance from each vertex to the shape), Approximate does not;
        FairWeight > 0 gives a fair fit."""
        path = os.path.join(SAMPLES, "rounded_box.obj")
        cage = s2n.make_cage(path, doc=self.doc)
        nurbs = s2n.make_nurbs(cage, progress=False)
        self.assertEqual(nurbs.Fit, "Approximate")
        points = [App.Vector(*map(float, p)) for p in subd2nurbs.read_cage(path).vertices]
        size = nurbs.Shape.BoundBox.DiagonalLength

        def miss():
            return max(nurbs.Shape.distToShape(Part.Vertex(p))[0] for p in points) / size

        self.assertGreater(miss(), 1e-3)
        nurbs.Fit = "Interpolate"
        self.doc.recompute()
        self.assertTrue(nurbs.Shape.isValid())
        self.assertLess(miss(), 1e-7)
        self.assertLess(nurbs.MaxResidual, 1e-9 * size)
        self.assertGreater(nurbs.MaxCageMove, 0)
        nurbs.FairWeight = 0.1
        self.doc.recompute()
        self.assertTrue(nurbs.Shape.isValid())
        self.assertGreater(nurbs.MaxResidual, 1e-9 * size)

    def test_polar_handling_and_a_triangulated_pole(self):
        """samples/capped_cylinder.obj: two 16-triangle fans (poles) and 112 quads."""
        path = os.path.join(SAMPLES, "capped_cylinder.obj")
        sizes = face_sizes(path)
        cage = s2n.make_cage(path, doc=self.doc)
        caps = s2n.make_nurbs(cage, progress=False, faces="PerQuad")  # polar caps, the default
        self.assertEqual(caps.PolarHandling, "Polar caps")
        self.assertTrue(caps.Shape.isValid())
        self.assertEqual(len(caps.Shape.Solids), 1)
        cap_faces = len(caps.Shape.Faces)
        caps.PolarHandling = "Catmull-Clark"
        self.doc.recompute()
        self.assertSolid(caps.Shape, sum(sizes))  # triangles present: one face per face corner
        self.assertLess(cap_faces, sum(sizes))
        # The same cage triangulated by FreeCAD's OBJ reader: quads come back, the fans stay
        # triangles and become the same polar caps.
        mesh = self.doc.addObject("Mesh::Feature", "cylinder_mesh")
        mesh.Mesh = Mesh.read(path)
        self.doc.recompute()
        from_mesh = s2n.make_nurbs(mesh, progress=False, faces="PerQuad")
        self.assertEqual(from_mesh.RecoveredQuads, sizes.count(4))
        self.assertEqual(from_mesh.KeptTriangles, sizes.count(3))
        self.assertEqual(len(from_mesh.Shape.Faces), cap_faces)
        self.assertTrue(from_mesh.Shape.isValid())
        if CLI:
            step = os.path.join(self.tmp, "cylinder.step")
            subprocess.run([CLI, "convert", path, "-o", step, "--faces", "per-quad", "--quiet"], check=True)
            self.assertEqual(len(Part.read(step).Faces), cap_faces)

    def test_same_solid_as_the_cli_step(self):
        self.assertTrue(CLI, "S2N_CLI is not set")
        for name in ("catmark_cube_creases0", "catmark_pyramid_creases0"):
            with self.subTest(name):
                path = corpus(name)
                step = os.path.join(self.tmp, name + ".step")
                subprocess.run([CLI, "convert", path, "-o", step, "--quiet"], check=True)
                from_cli = Part.read(step)
                nurbs = s2n.make_nurbs(s2n.make_cage(path, doc=self.doc), progress=False)
                self.assertEqual(len(nurbs.Shape.Faces), len(from_cli.Faces))
                self.assertEqual(len(nurbs.Shape.Edges), len(from_cli.Edges))
                self.assertLessEqual(abs(nurbs.Shape.Area - from_cli.Area), 1e-9 * from_cli.Area)
                self.assertLessEqual(abs(nurbs.Shape.Volume - from_cli.Volume), 1e-9 * from_cli.Volume)

    def test_check_quality_reports_and_names_edges(self):
        nurbs = s2n.make_nurbs(s2n.make_cage(corpus("catmark_cube_creases0"), doc=self.doc), progress=False)
        report = s2n.check_quality(nurbs, count=3)
        self.assertTrue(report["valid"])
        self.assertEqual(report["faces"], 6)
        self.assertEqual(len(report["worst_edges"]), 3)
        for edge, angle, gap in report["worst_edges"]:
            index = int(edge[4:])
            self.assertTrue(1 <= index <= len(nurbs.Shape.Edges))
            self.assertGreaterEqual(angle, 0)
        self.assertLess(report["max_gap"], 1e-9 * 10)

    def test_check_quality_gives_the_smallest_radius_as_occt_measures_it(self):
        # Oracle: OCCT's own principal curvatures of the face at the point reported (the torus's
        # tube inside, its saddle at the hole outside).
        nurbs = s2n.make_nurbs(s2n.make_cage(corpus("catmark_torus"), doc=self.doc), progress=False)
        report = s2n.check_quality(nurbs, highlight=False)
        for side in ("inward", "outward"):
            at = report["smallest_radius"][side]
            self.assertIsNotNone(at, side)
            point = App.Vector(*at["point"])
            faces = [f for f in nurbs.Shape.Faces if f.distToShape(Part.Vertex(point))[0] < 1e-7]
            self.assertTrue(faces, side)
            face = faces[0]
            u, v = face.Surface.parameter(point)
            k = [face.Surface.curvature(u, v, which) for which in ("Max", "Min")]
            # One of OCCT's two principal radii there (inward: the convex one, outward: the
            # concave one; at the torus's saddle the two have opposite signs).
            self.assertAlmostEqual(min(abs(at["radius"] - 1 / abs(c)) for c in k), 0, delta=1e-6 * at["radius"])
        self.assertEqual(report["self_intersections"], 0)
        self.assertEqual(report["overlaps"], 0)
        self.assertEqual(report["intersection_witnesses"], [])

    def test_check_quality_names_overlapping_parts_as_occt_finds_them(self):
        # Two cube cages 0.4 apart interpenetrate: OCCT's own checker (Shape.check(True),
        # BOPAlgo_ArgumentAnalyzer) refuses the shape, and check_quality names faces of both cubes
        # through a point they share. 1.2 apart: both clean.
        def cubes(dx):
            lines = []
            for c in (0, dx):
                for k in range(8):
                    lines.append("v %g %g %g" % ((0.5 if k & 1 else -0.5) + c, (0.5 if k & 2 else -0.5) + 0.1 * c,
                                                 (0.5 if k & 4 else -0.5) + 0.2 * c))
            for base in (1, 9):
                for f in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
                    lines.append("f " + " ".join(str(base + i) for i in f))
            path = os.path.join(self.tmp, "cubes_%g.obj" % dx)
            with open(path, "w") as out:
                out.write("\n".join(lines) + "\n")
            return s2n.make_nurbs(s2n.make_cage(path, doc=self.doc), progress=False)
        apart = s2n.check_quality(cubes(1.2), highlight=False)
        self.assertEqual((apart["self_intersections"], apart["overlaps"]), (0, 0))
        self.assertEqual(apart["intersection_witnesses"], [])
        cubes(1.2).Shape.check(True)  # raises if OCCT finds anything
        nurbs = cubes(0.4)
        report = s2n.check_quality(nurbs, highlight=False)
        self.assertEqual(report["self_intersections"], 0)
        self.assertGreater(report["overlaps"], 0)
        self.assertEqual(report["overlapping_parts"], [(0, 1)])
        with self.assertRaises(Exception):
            nurbs.Shape.check(True)
        solids = nurbs.Shape.Solids
        self.assertEqual(len(solids), 2)
        for w in report["intersection_witnesses"]:
            self.assertEqual(w["kind"], "overlap")
            self.assertEqual(len(w["faces"]), 2)
            point = Part.Vertex(App.Vector(*w["point"]))
            for solid in solids:  # on the surface of each cube
                self.assertLess(solid.distToShape(point)[0], 1e-6)

    def test_color_map_has_the_previews_colours(self):
        # The same per-vertex colours as the module's (and so the CLI's --preview) tessellation.
        path = corpus("catmark_cube_creases0")
        nurbs = s2n.make_nurbs(s2n.make_cage(path, doc=self.doc), progress=False)
        for coloring in ("Curvature", "Deviation", "Zebra"):
            with self.subTest(coloring):
                cm = s2n.make_color_map(nurbs, coloring, samples=5)
                expected = subd2nurbs.convert(subd2nurbs.read_cage(path), brep=False, preview=coloring.lower(),
                                              preview_samples=5).preview
                self.assertEqual(len(cm.Points), len(expected["positions"]))
                self.assertEqual(len(cm.Colors), len(expected["colors"]))
                self.assertEqual(list(cm.Triangles), [int(i) for i in expected["triangles"].reshape(-1)])
                for got, want in zip(cm.Colors, expected["colors"]):
                    for a, b in zip(got[:3], want):
                        self.assertAlmostEqual(a, float(b), delta=1e-6)
                for got, want in zip(cm.Points, expected["positions"]):
                    self.assertAlmostEqual((got - App.Vector(*map(float, want))).Length, 0, delta=1e-6)
        cm.Coloring = "Zebra"
        cm.Samples = 3
        self.doc.recompute()
        self.assertTrue(cm.isValid())
        self.assertEqual(len(cm.Points), 6 * 3 * 3)  # 6 patches, 3 x 3 points each
        with self.assertRaises(TypeError):
            s2n.make_color_map(s2n.make_cage(path, doc=self.doc))

    def test_one_conversion_serves_the_solid_the_check_and_the_color_map(self):
        """The NURBS object keeps its last conversion, keyed by its inputs: check_quality and the
        colour map use it; a change converts again, a failure keeps the last valid shape and a
        return to the last good settings needs no conversion."""
        path = corpus("catmark_cube_creases0")
        calls = []
        real = subd2nurbs.convert

        def counting(*args, **kwargs):
            calls.append(kwargs)
            return real(*args, **kwargs)

        subd2nurbs.convert = counting
        try:
            nurbs = s2n.make_nurbs(s2n.make_cage(path, doc=self.doc), progress=False)
            self.assertEqual(len(calls), 1)
            s2n.check_quality(nurbs, highlight=False)
            cm = s2n.make_color_map(nurbs, "Deviation", samples=4)
            cm.Coloring = "Zebra"
            self.doc.recompute()
            self.assertTrue(cm.isValid())
            self.assertEqual(len(calls), 1)
            nurbs.Level = 1
            self.doc.recompute()
            self.assertEqual(len(calls), 2)
            self.assertEqual(calls[-1].get("level"), 1)
            self.assertTrue(nurbs.isValid() and cm.isValid())
            # The colour map follows the new conversion: the module's preview of level 1.
            want = real(subd2nurbs.read_cage(path), level=1, brep=False, preview="zebra", preview_samples=4).preview
            self.assertEqual(list(cm.Triangles), [int(i) for i in want["triangles"].reshape(-1)])
            for got, p in zip(cm.Points, want["positions"]):
                self.assertAlmostEqual((got - App.Vector(*map(float, p))).Length, 0, delta=1e-6)
            area = nurbs.Shape.Area
            nurbs.Level = -1  # refused: the last valid shape stays, with the rule as the message
            self.doc.recompute()
            self.assertFalse(nurbs.isValid())
            self.assertIn("Level must be 0 .. 12", nurbs.getStatusString())
            self.assertAlmostEqual(nurbs.Shape.Area, area, delta=1e-12 * area)
            failed = len(calls)
            nurbs.Level = 1
            self.doc.recompute()
            self.assertTrue(nurbs.isValid())
            self.assertEqual(len(calls), failed)  # the kept result still matches
            self.assertAlmostEqual(nurbs.Shape.Area, area, delta=1e-12 * area)
        finally:
            subd2nurbs.convert = real

    def test_undo_removes_the_conversion(self):
        self.doc.UndoMode = 1
        cage = s2n.make_cage(corpus("catmark_cube"), doc=self.doc)
        before = self.names()
        s2n.make_nurbs(cage, progress=False)
        self.assertEqual(len(self.names()), len(before) + 1)
        self.doc.undo()
        self.assertEqual(self.names(), before)
