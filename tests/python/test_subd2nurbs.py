"""Tests of the Python module subd2nurbs (label python), run by Debian's /usr/bin/python3 with
unittest: PYTHONPATH holds build/python; SUBD2NURBS_CLI is the subd2nurbs executable and
SUBD2NURBS_CORPUS_DIR the OpenSubdiv corpus.

Oracles: counts that follow from the cage (one face per quad, one per corner of an n-gon;
Euler's formula for refinement), OCCT's own measurement of the BREP text, the CLI's output
for the same cage (the module must produce the same B-rep byte for byte), and exact identities
of clamped B-splines (pole counts from the knots)."""

import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import subd2nurbs as s2n

CORPUS = os.environ.get("SUBD2NURBS_CORPUS_DIR", "")
CLI = os.environ.get("SUBD2NURBS_CLI", "")


def corpus(name):
    return os.path.join(CORPUS, name + ".obj")


def cube_cage():
    """The unit cube as a quad cage (counter-clockwise seen from outside)."""
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    return v, faces


def prism_cage(n=5):
    """An n-gonal prism: two n-gons and n quads (n-gons are split by one CC step, so the
    B-rep has one face per face corner: 2n + 4n)."""
    ring = [[math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)] for k in range(n)]
    v = [[x, y, 0.0] for x, y in ring] + [[x, y, 1.0] for x, y in ring]
    bottom = list(reversed(range(n)))
    top = [n + k for k in range(n)]
    sides = [[k, (k + 1) % n, n + (k + 1) % n, n + k] for k in range(n)]
    return np.array(v), [bottom, top] + sides


class CageConstruction(unittest.TestCase):
    def test_from_numpy_and_lists_agree(self):
        v, f = cube_cage()
        a = s2n.Cage(v, f)
        b = s2n.Cage(v.tolist(), np.array(f, dtype=np.int64))
        self.assertEqual(a.num_vertices, 8)
        self.assertEqual(a.num_faces, 6)
        self.assertEqual(a.faces, f)
        self.assertEqual(b.faces, f)
        np.testing.assert_array_equal(a.vertices, b.vertices)
        self.assertEqual(a.face_sizes.tolist(), [4] * 6)

    def test_read_obj_matches_file(self):
        cage = s2n.read_obj(corpus("catmark_cube_creases0"))
        self.assertEqual(cage.vertices.shape, (8, 3))
        self.assertEqual(cage.num_faces, 6)
        self.assertTrue(cage.creases)  # the file has crease tags
        for a, b, s in cage.creases:
            self.assertTrue(0 <= a < 8 and 0 <= b < 8 and s >= 0)

    def test_info_counts(self):
        v, f = prism_cage(5)
        i = s2n.info(s2n.Cage(v, f))
        self.assertEqual(i["vertices"], 10)
        self.assertEqual(i["faces"], 7)
        self.assertEqual(i["edges"], 15)
        self.assertEqual(i["euler_characteristic"], 2)
        self.assertTrue(i["closed"])
        self.assertEqual(i["face_sizes"], {4: 5, 5: 2})

    def test_refine_counts_follow_euler(self):
        v, f = prism_cage(5)
        cage = s2n.Cage(v, f)
        one = s2n.refine(cage, 1)
        # One CC step: a vertex per vertex, edge and face; a quad per face corner.
        self.assertEqual(one.num_vertices, 10 + 15 + 7)
        self.assertEqual(one.num_faces, 5 * 4 + 2 * 5)
        self.assertEqual(set(one.face_sizes.tolist()), {4})
        two = s2n.refine(cage, 2)
        self.assertEqual(two.num_faces, 4 * one.num_faces)
        self.assertEqual(s2n.info(two)["euler_characteristic"], 2)
        self.assertEqual(s2n.refine(cage, 0).faces, cage.faces)


class BadInput(unittest.TestCase):
    def assertCageError(self, fn, element, index=None, fragment=None, code=None):
        with self.assertRaises(s2n.CageError) as cm:
            fn()
        e = cm.exception
        self.assertIsInstance(e, ValueError)
        self.assertEqual(e.element, element, str(e))
        if index is not None:
            self.assertEqual(e.index, index, str(e))
        if fragment is not None:
            self.assertIn(fragment, str(e))
        if code is not None:
            self.assertEqual(e.code, code)
        return e

    def test_bad_arrays_name_the_element(self):
        v, f = cube_cage()
        self.assertCageError(lambda: s2n.Cage(v[:, :2], f), "vertices", fragment="shape (n, 3)")
        self.assertCageError(lambda: s2n.Cage(np.zeros((0, 3)), f), "vertices", code="empty-mesh")
        w = v.copy()
        w[5, 1] = np.nan
        self.assertCageError(lambda: s2n.Cage(w, f), "vertex", 5, code="non-finite-coordinate")
        self.assertCageError(lambda: s2n.Cage(v, f[:3] + [[0, 1, 99]]), "face", 3,
                             "face 3: vertex index 99 out of range", "index-out-of-range")
        self.assertCageError(lambda: s2n.Cage(v, f + [[0, -1, 2]]), "face", 6)
        self.assertCageError(lambda: s2n.Cage(v, [[0, 1]]), "face", 0, code="face-too-small")
        self.assertCageError(lambda: s2n.Cage(v, [[0, 1, 1, 2]]), "face", 0, code="repeated-vertex-in-face")
        self.assertCageError(lambda: s2n.Cage(v, [[0, 1.5, 2]]), "face", 0, "not an integer")
        self.assertCageError(lambda: s2n.Cage(v, []), "faces", code="empty-mesh")
        self.assertCageError(lambda: s2n.Cage(v, f, creases=[(0, 8, 1.0)]), "crease", 0, code="invalid-tag")
        self.assertCageError(lambda: s2n.Cage(v, f, creases=[(0, 1, -1.0)]), "crease", 0, "sharpness")
        self.assertCageError(lambda: s2n.Cage(v, f, creases=[(0, 1)]), "crease", 0)
        self.assertCageError(lambda: s2n.Cage(v, f, corners=[(9, 1.0)]), "corner", 0)
        self.assertCageError(lambda: s2n.Cage(v, f, holes=[6]), "hole", 0)
        with self.assertRaises(s2n.SettingsError):
            s2n.Cage(v, f, boundary="sometimes")

    def test_topology_errors_come_from_the_core(self):
        v, f = cube_cage()
        # Flip one face: its edges run the same way as its neighbours'.
        flipped = [list(reversed(f[0]))] + f[1:]
        e = self.assertCageError(lambda: s2n.convert(s2n.Cage(v, flipped)), "face", code="inconsistent-orientation")
        self.assertIn("orient", str(e))
        # A crease tag on two vertices that share no edge (0 and 7 are opposite corners).
        self.assertCageError(lambda: s2n.Cage(v, f, creases=[(0, 7, 1.0)]).validate(), "tag",
                             code="invalid-tag")

    def test_files(self):
        with self.assertRaises(s2n.CageError) as cm:
            s2n.read_obj("/nonexistent/cage.obj")
        self.assertEqual(cm.exception.file, "/nonexistent/cage.obj")
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "bad.obj")
            with open(p, "w") as out:
                out.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
            with self.assertRaises(s2n.CageError) as cm:
                s2n.read_obj(p)
            self.assertEqual(cm.exception.line, 4, str(cm.exception))
            self.assertIn("bad.obj:4", str(cm.exception))

    def test_settings(self):
        v, f = cube_cage()
        cage = s2n.Cage(v, f)
        for kwargs in ({"level": -1}, {"level": 1.5}, {"tolerance": 0}, {"tolerance": float("nan")},
                       {"level": 1, "tolerance": 0.1}, {"absolute": True}):
            with self.assertRaises(s2n.SettingsError, msg=str(kwargs)):
                s2n.convert(cage, **kwargs)
        with self.assertRaises(s2n.SettingsError):
            s2n.refine(cage, -1)
        with self.assertRaises(TypeError):
            s2n.convert(v)

    def test_resource_limits(self):
        """max_faces / max_memory (issue #14): the refine estimate is exact, so the limit at
        the real output face count passes and one below refuses; convert refuses before any
        work, naming the estimate and the override."""
        v, f = cube_cage()
        cage = s2n.Cage(v, f)
        for levels in (1, 2, 3):
            faces = s2n.refine(cage, levels).num_faces
            s2n.refine(cage, levels, max_faces=faces)
            with self.assertRaises(s2n.SettingsError) as e:
                s2n.refine(cage, levels, max_faces=faces - 1)
            self.assertEqual(e.exception.code, "resource-limit")
            self.assertIn("about %d faces" % faces, str(e.exception))
        # The cube's 24 irregular corners at level 12: 6 + 24 * (3 * (2 + 12) + 2) = 1062 pieces
        # estimated (the adaptive builder refines only towards the corners; it builds 960).
        s2n.convert(cage, level=12, max_faces=1062, brep=False)
        with self.assertRaises(s2n.SettingsError) as e:
            s2n.convert(cage, level=12, max_faces=1061)
        self.assertIn("max_faces", str(e.exception))
        with self.assertRaises(s2n.SettingsError) as e:
            s2n.convert(cage, max_memory="1K")
        self.assertIn("memory", str(e.exception))
        self.assertEqual(s2n.convert(cage, max_memory="1G", max_faces=1e3, brep=False).num_patches, 6)
        for bad in ({"max_faces": 0}, {"max_faces": "x"}, {"max_memory": "12Q"}, {"max_memory": -1}):
            with self.assertRaises(s2n.SettingsError, msg=str(bad)):
                s2n.convert(cage, **bad)

    def test_hostile_cages_name_the_element(self):
        v, f = cube_cage()
        v = np.array(v, dtype=float)
        v[6, 0] = 1e200
        with self.assertRaises(s2n.CageError) as e:
            s2n.info(s2n.Cage(v, f))
        self.assertEqual(e.exception.code, "coordinate-out-of-range")
        v, f = cube_cage()
        with self.assertRaises(s2n.CageError) as e:
            s2n.convert(s2n.Cage(v, f, holes=list(range(6))))
        self.assertIn("every face", str(e.exception))
        with tempfile.TemporaryDirectory() as d:
            fifo = os.path.join(d, "pipe.obj")
            os.mkfifo(fifo)
            with self.assertRaises(s2n.CageError) as e:
                s2n.read_cage(fifo)
            self.assertIn("FIFO", str(e.exception))


class Conversion(unittest.TestCase):
    def test_cube_patches_are_clamped_bicubic_nurbs(self):
        v, f = cube_cage()
        r = s2n.convert(s2n.Cage(v, f))
        self.assertEqual(r.num_patches, 6)
        for p in r.patches:
            for d in "uv":
                deg, mults, knots = p["degree_" + d], p["mults_" + d], p["knots_" + d]
                self.assertEqual(deg, 3)
                self.assertEqual(mults[0], 4)
                self.assertEqual(mults[-1], 4)
                self.assertTrue(np.all(np.diff(knots) > 0))
            nu, nv, three = p["poles"].shape
            self.assertEqual(three, 3)
            self.assertEqual(nu, int(np.sum(p["mults_u"])) - 4)
            self.assertEqual(nv, int(np.sum(p["mults_v"])) - 4)
            self.assertTrue(p["weights"] is None or p["weights"].shape == (nu, nv))
            self.assertEqual(len(p["base_faces"]), 1)
        # The limit surface of a convex cage lies inside its hull.
        poles = np.concatenate([p["poles"].reshape(-1, 3) for p in r.patches])
        self.assertTrue(np.all(poles >= -1e-12) and np.all(poles <= 1 + 1e-12))

    def test_round_trip_numpy_to_brep_text_measured_by_occt(self):
        for n in (3, 5, 6):
            v, f = prism_cage(n)
            r = s2n.convert(s2n.Cage(v, f), level=0, faces="per-quad")
            m = s2n.brep_summary(r.brep_text)
            expected_faces = 2 * n + 4 * n  # one face per corner of every face (n-gons split)
            self.assertTrue(m["valid"], m["check_message"])
            self.assertEqual(m["solids"], 1)
            self.assertEqual(m["faces"], expected_faces)
            self.assertEqual(r.brep["faces"], expected_faces)
            self.assertEqual(m["free_edges"], 0)
            self.assertGreater(m["volume"], 0)
            self.assertLess(m["max_gap"], 1e-9 * r.model_size)
            self.assertEqual(r.report["brep"]["faces"], expected_faces)
            self.assertEqual(r.report["patches"]["total"], expected_faces)

    def test_crease_tags_reach_the_patches(self):
        v, f = cube_cage()
        # Every edge of the top face infinitely sharp: four C0 curves.
        creases = [(4, 5, 10.0), (5, 7, 10.0), (7, 6, 10.0), (6, 4, 10.0)]
        r = s2n.convert(s2n.Cage(v, f, creases=creases))
        self.assertEqual(r.report["curves"]["c0"], 4)
        self.assertEqual(s2n.convert(s2n.Cage(v, f)).report["curves"]["c0"], 0)

    def test_level_and_tolerance(self):
        cage = s2n.read_obj(corpus("catmark_cube"))
        r0 = s2n.convert(cage, level=0, brep=False)
        r1 = s2n.convert(cage, level=1, brep=False)
        self.assertIsNone(r0.brep_text)
        self.assertEqual(r1.report["level"], r0.report["level"] + 1)
        self.assertLess(r1.report["deviation"]["max"], r0.report["deviation"]["max"])
        t = 0.25 * r0.report["deviation"]["relative"]
        rt = s2n.convert(cage, tolerance=t, brep=False)
        tol = rt.report["deviation"]["tolerance"]
        self.assertTrue(tol["met"])
        self.assertLessEqual(rt.report["deviation"]["max"], t * r0.model_size)
        self.assertGreaterEqual(tol["extra_levels_used"], 1)

    def test_progress_is_reported(self):
        stages = []
        s2n.convert(s2n.read_obj(corpus("catmark_cube")), progress=lambda s, x: stages.append((s, x)))
        names = [s for s, _ in stages]
        self.assertIn("building patches", names)
        self.assertIn("building the B-rep", names)
        self.assertTrue(all(0 <= x <= 1 for _, x in stages))
        self.assertEqual(max(x for s, x in stages if s == "building the B-rep"), 1.0)
        # Each line names its stage (the pipeline's Stage), whatever its wording.
        self.assertEqual([s.key for s, _ in stages if s.startswith("building patches")][0], "patches")
        self.assertEqual({s.key for s, _ in stages} - {"fit"},
                         {"patches", "deviation", "packing", "continuity", "brep"})

    def test_progress_returning_false_cancels(self):
        # Returning False (not None) stops the conversion at that call: Cancelled, no result;
        # the stages after it never run.
        cube = s2n.read_obj(corpus("catmark_cube"))
        for stop in ("patches", "continuity", "brep"):
            keys = []

            def progress(stage, fraction):
                keys.append(stage.key)
                return False if stage.key == stop else None
            with self.assertRaises(s2n.Cancelled):
                s2n.convert(cube, progress=progress)
            self.assertEqual(keys[-1], stop)
            self.assertEqual(keys.count(stop), 1)
        self.assertTrue(issubclass(s2n.Cancelled, s2n.Subd2NurbsError))
        # Falsy values other than False do not cancel.
        r = s2n.convert(cube, progress=lambda stage, fraction: 0)
        self.assertTrue(r.brep["valid"])

    def test_worst_edges_are_edges_of_the_shape(self):
        r = s2n.convert(s2n.read_obj(corpus("catmark_cube")))
        worst = r.worst_edges(3)
        self.assertEqual(len(worst), 3)
        for edge, angle, gap in worst:
            self.assertTrue(1 <= edge <= r.brep["edges"])
            self.assertGreaterEqual(angle, 0)
        self.assertGreaterEqual(worst[0][1], worst[-1][1])

    def test_same_brep_and_report_as_the_cli(self):
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        for name in ("catmark_cube_creases0", "catmark_nonquads"):
            with tempfile.TemporaryDirectory() as d:
                out, rep = os.path.join(d, "out.brep"), os.path.join(d, "rep.json")
                subprocess.run([CLI, "convert", corpus(name), "-o", out, "--report", rep, "-q"], check=True)
                r = s2n.convert(s2n.read_obj(corpus(name)))
                with open(out) as fh:
                    self.assertEqual(fh.read(), "DBRep_DrawableShape\n" + r.brep_text)
                with open(rep) as fh:
                    cli = json.load(fh)
                for key in ("patches", "curves", "fans", "brep", "level", "warnings"):
                    self.assertEqual(r.report[key], cli[key], key)
                self.assertEqual(r.report["deviation"]["max"], cli["deviation"]["max"])

    def test_an_unused_vertex_does_not_set_the_model_size(self):
        """#32 item 2: the model size (and every tolerance scaled by it) is the diagonal of the
        vertices that faces use; a vertex at 1e6 that no face uses changes none of them."""
        v, f = cube_cage()
        alone = s2n.convert(s2n.Cage(v, f))
        far = s2n.convert(s2n.Cage(np.vstack([v, [[1e6, 1e6, 1e6]]]), f))
        self.assertAlmostEqual(alone.model_size, math.sqrt(3), places=14)
        self.assertEqual(far.model_size, alone.model_size)
        self.assertEqual(far.report["model_size"], alone.report["model_size"])
        self.assertEqual(far.report["brep"], alone.report["brep"])
        self.assertEqual(far.report["deviation"], alone.report["deviation"])
        tol = far.report["deviation"]["tolerance"]
        self.assertTrue(tol["default"])
        self.assertTrue(tol["met"])
        self.assertLess(tol["requested_model_units"], 0.01 * alone.model_size)
        self.assertLessEqual(far.report["deviation"]["max"], tol["requested_model_units"])
        self.assertEqual(far.brep_text, alone.brep_text)
        # A cage whose faces all sit at one point has no surface, whatever unused vertex is far away.
        point = np.vstack([np.zeros((8, 3)), [[1, 1, 1]]])
        with self.assertRaises(s2n.CageError) as e:
            s2n.convert(s2n.Cage(point, f))
        self.assertIn("all its vertices coincide", str(e.exception))


class Triangles(unittest.TestCase):
    def test_from_triangles_recovers_the_cube_and_converts(self):
        v, f = cube_cage()
        tris = [t for q in f for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])]
        cage = s2n.from_triangles(v, tris)
        self.assertEqual(cage.quad_recovery["quads"], 6)
        self.assertEqual(cage.quad_recovery["triangles_kept"], 0)
        self.assertEqual(sorted(sorted(x) for x in cage.faces), sorted(sorted(x) for x in f))
        self.assertEqual(len(cage.sources), 6)
        r = s2n.convert(cage)
        self.assertEqual(s2n.brep_summary(r.brep_text)["faces"], 6)

    def test_triangulated_polar_sample_recovers_its_cage_and_caps(self):
        samples = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples")
        cage = s2n.read_cage(os.path.join(samples, "capped_cylinder.obj"))
        tris = [[f[0], f[k], f[k + 1]] for f in cage.faces for k in range(1, len(f) - 1)]
        rebuilt = s2n.from_triangles(cage.vertices, tris)
        self.assertEqual(sorted(map(sorted, rebuilt.faces)), sorted(map(sorted, cage.faces)))
        self.assertEqual(rebuilt.quad_recovery["fan_vertices"], 2)
        self.assertEqual(s2n.convert(rebuilt).brep["faces"], s2n.convert(cage).brep["faces"])
        with self.assertRaises(s2n.SettingsError):
            s2n.convert(cage, radial_steps=3)
        with self.assertRaises(s2n.SettingsError):
            s2n.convert(cage, polar_lambda=0)
        off = s2n.convert(cage, polar=False, brep=False, faces="per-quad")
        self.assertEqual(off.num_patches, int(cage.face_sizes.sum()))  # one patch per face corner

    def test_packed_faces_list_their_quads(self):
        # catmark_torus: 8 x 4 regular quads, one packed face over [0, 8] x [0, 4].
        cage = s2n.read_cage(corpus("catmark_torus"))
        packed = s2n.convert(cage)
        quads = s2n.convert(cage, faces="per-quad")
        self.assertEqual(packed.num_patches, 1)
        self.assertEqual(quads.num_patches, 32)
        p = packed.patches[0]
        self.assertEqual(p["cells"].shape, (32, 5))
        self.assertEqual(sorted(p["cells"][:, 0]), list(range(32)))
        self.assertEqual(sorted((p["knots_u"][-1], p["knots_v"][-1])), [4.0, 8.0])  # one unit per quad
        self.assertEqual(sorted(p["poles"].shape[:2]), [7, 11])
        self.assertIsNone(quads.patches[0]["cells"])
        self.assertEqual(packed.report["faces"]["total"], 1)
        self.assertEqual(packed.brep["faces"], 1)
        self.assertTrue(packed.brep["valid"] and packed.brep["is_solid"])
        a, b = s2n.brep_summary(packed.brep_text), s2n.brep_summary(quads.brep_text)
        self.assertEqual((a["solids"], a["faces"], b["faces"]), (1, 1, 32))
        # OCCT's GProp integrates to about 1e-6 relative: the same solid within that.
        self.assertLess(abs(a["volume"] - b["volume"]), 1e-6 * b["volume"])
        self.assertLess(abs(a["area"] - b["area"]), 1e-6 * b["area"])
        with self.assertRaises(s2n.SettingsError):
            s2n.convert(cage, faces="quads")

    def test_separate_poles_makes_caps_of_low_valence_poles(self):
        n = 5  # a capped prism whose valence-5 poles BP cannot take directly
        prof = [(1 / 3, 1.2), (2 / 3, 1.1), (1, 1), (1, 0), (1, -1), (2 / 3, -1.1), (1 / 3, -1.2)]
        v = [[0, 0, 1.25]] + [[r * math.cos(2 * math.pi * j / n), r * math.sin(2 * math.pi * j / n), z]
                              for r, z in prof for j in range(n)] + [[0, 0, -1.25]]
        ring = lambda i, j: 1 + i * n + j % n
        f = [[0, ring(0, j), ring(0, j + 1)] for j in range(n)]
        f += [[ring(i, j + 1), ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)] for i in range(len(prof) - 1) for j in range(n)]
        f += [[len(v) - 1, ring(len(prof) - 1, j + 1), ring(len(prof) - 1, j)] for j in range(n)]
        cage = s2n.Cage(v, f)
        plain = s2n.convert(cage, brep=False)
        self.assertEqual(plain.report["patches"]["polar_caps"], 0)
        sep = s2n.convert(cage, separate_poles=True)
        self.assertEqual(sep.report["patches"]["polar_caps"], 2)
        self.assertEqual(sorted(sep.report["polar"]["separated_poles"]), [0, len(v) - 1])
        self.assertTrue(sep.brep["valid"])
        self.assertEqual(sep.report["brep"]["type"], "solid")
        with self.assertRaises(s2n.SettingsError):
            s2n.convert(cage, polar=False, separate_poles=True)

    def test_from_triangles_keeps_a_pole_fan(self):
        n = 8
        v = [[0, 0, 0]] + [[math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n), 0] for k in range(n)]
        tris = [[0, 1 + k, 1 + (k + 1) % n] for k in range(n)]
        cage = s2n.from_triangles(v, tris)
        self.assertEqual(cage.quad_recovery["fan_vertices"], 1)
        self.assertEqual(cage.quad_recovery["quads"], 0)
        self.assertEqual(cage.num_faces, n)


class UsdInput(unittest.TestCase):
    """read_cage of USD files (issue #29): variants by keyword, what was read in cage.usd, the
    same cage as the command line reads (its `info --json` counts)."""

    geo = os.path.join(CORPUS, "..", "usd", "geo.usda")

    def test_variants_select_creases_corners_holes(self):
        default = s2n.read_cage(self.geo)
        self.assertEqual(default.usd["variant_sets"][0]["selection"], "quad_holes")
        self.assertEqual(len(default.holes), default.usd["meshes"][0]["holes"])
        self.assertEqual(len(default.holes), 4)  # holeIndices = [0, 1, 2, 3] in the file
        edges = s2n.read_cage(self.geo, variant={"geo": "quad_creases", "creases": "edges"})
        self.assertEqual(len(edges.creases), 6)  # creaseLengths = [2, 2, 2, 2, 2, 2]
        self.assertTrue(all(c[2] == 100 for c in edges.creases))  # creaseSharpnesses, as written
        corners = s2n.read_cage(self.geo, variant=["geo=quad_creases", "creases=corners"])
        self.assertEqual(sorted(c[0] for c in corners.corners), [0, 2])  # cornerIndices = [0, 2]
        self.assertTrue(np.array_equal(np.asarray(corners.vertices), np.asarray(edges.vertices)))
        with self.assertRaises(s2n.SettingsError):
            s2n.read_cage(self.geo, variant="no-equals-sign")
        with self.assertRaises(s2n.CageError):
            s2n.read_cage(self.geo, variant="size=big")

    def test_same_cage_as_the_command_line(self):
        cli = os.environ.get("SUBD2NURBS_CLI")
        if not cli:
            self.skipTest("SUBD2NURBS_CLI not set")
        out = subprocess.run([cli, "info", "--json", "--variant", "geo=quad_creases", "--variant", "creases=edges",
                              self.geo], capture_output=True, text=True, check=True).stdout
        info = json.loads(out)
        cage = s2n.read_cage(self.geo, variant={"geo": "quad_creases", "creases": "edges"})
        self.assertEqual((info["vertices"], info["faces"]), (cage.num_vertices, cage.num_faces))
        self.assertEqual(info["creases"]["infinite_edges"], len(cage.creases))


class Diagnostics(unittest.TestCase):
    def test_many_poles_that_are_not_polar_give_one_note(self):
        """A triangulated torus: every vertex is an all-triangle vertex of valence 6 and none
        is a polar structure. The CLI says so in one summary line (none with --quiet); the
        report, the Python warnings and diagnostics still name each vertex (issue #15)."""
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        n, m = 12, 8
        v = [[(3 + math.cos(2 * math.pi * j / m)) * math.cos(2 * math.pi * i / n),
              (3 + math.cos(2 * math.pi * j / m)) * math.sin(2 * math.pi * i / n), math.sin(2 * math.pi * j / m)]
             for i in range(n) for j in range(m)]
        k = lambda i, j: (i % n) * m + j % m
        triangles = []
        for i in range(n):
            for j in range(m):
                triangles += [[k(i, j), k(i + 1, j), k(i + 1, j + 1)], [k(i, j), k(i + 1, j + 1), k(i, j + 1)]]
        with tempfile.TemporaryDirectory() as d:
            obj = os.path.join(d, "torus.obj")
            with open(obj, "w") as out:
                out.writelines("v %r %r %r\n" % tuple(p) for p in v)
                out.writelines("f %d %d %d\n" % tuple(x + 1 for x in t) for t in triangles)
            report = os.path.join(d, "r.json")
            r = subprocess.run([CLI, "convert", obj, "-o", os.path.join(d, "t.json"), "--level", "0", "--report", report],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            notes = [line for line in r.stderr.splitlines() if "polar structure" in line]
            self.assertEqual(notes, ["subd2nurbs: note: %d vertices are not polar structures, Catmull-Clark is used "
                                     "there (%d: their rings do not form one); `subd2nurbs info --json` lists them all"
                                     % (n * m, n * m)], r.stderr)
            with open(report) as f:
                listed = json.load(f)
            self.assertEqual(len(listed["polar"]["not_polar"]), n * m)
            self.assertEqual(sum("is not a polar structure" in w for w in listed["warnings"]), n * m)
            info = subprocess.run([CLI, "info", obj, "--json"], capture_output=True, text=True, check=True)
            self.assertEqual(len(json.loads(info.stdout)["not_polar"]), n * m)
            quiet = subprocess.run([CLI, "convert", obj, "-o", os.path.join(d, "t.json"), "--level", "0", "-q"],
                                   capture_output=True, text=True)
            self.assertEqual((quiet.returncode, quiet.stderr), (0, ""))
            result = s2n.convert(s2n.read_cage(obj), level=0, brep=False)
        self.assertEqual(result.warnings, listed["warnings"])
        poles = [x for x in result.diagnostics if x["code"] == "pole_not_polar"]
        self.assertEqual(sorted(x["element"] for x in poles), list(range(n * m)))
        self.assertTrue(all(x["severity"] == "note" and not x["message"].startswith("subd2nurbs") for x in poles))


class Preview(unittest.TestCase):
    def test_preview_colours_match_the_cli_glb(self):
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
        import render_glb
        cage_file = corpus("catmark_cube_creases0")
        for color in ("curvature", "deviation", "zebra"):
            r = s2n.convert(s2n.read_cage(cage_file), brep=False, preview=color, preview_samples=6)
            p = r.preview
            self.assertEqual(p["positions"].shape, p["colors"].shape)
            self.assertEqual(p["triangles"].shape[1], 3)
            self.assertLess(int(p["triangles"].max()), len(p["positions"]))
            with tempfile.TemporaryDirectory() as d:
                glb = os.path.join(d, "p.glb")
                subprocess.run([CLI, "convert", cage_file, "-o", os.path.join(d, "c.brep"), "-q", "--preview", glb,
                                "--color", color, "--preview-samples", "6"], check=True)
                pos, _, col, idx = render_glb.read_glb(glb)
            self.assertEqual(len(pos), p["positions"].size)
            np.testing.assert_array_equal(np.array(col, dtype=np.float32).reshape(-1, 3), p["colors"])
            np.testing.assert_array_equal(np.array(pos, dtype=np.float32).reshape(-1, 3), p["positions"])
            np.testing.assert_array_equal(np.array(idx).reshape(-1, 3), p["triangles"])
        with self.assertRaises(s2n.SettingsError):
            s2n.convert(s2n.read_cage(cage_file), preview="rainbow")


class Writing(unittest.TestCase):
    def test_write_step_iges_brep_like_the_cli(self):
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        r = s2n.convert(s2n.read_cage(corpus("catmark_cube_creases0")))
        with tempfile.TemporaryDirectory() as d:
            subprocess.run([CLI, "convert", corpus("catmark_cube_creases0"), "-o", os.path.join(d, "cli.step"), "-q"],
                           check=True)
            cli = s2n.file_summary(os.path.join(d, "cli.step"))
            for name in ("a.step", "a.stp", "a.iges", "a.brep"):
                r.write(os.path.join(d, name), schema="ap242" if name == "a.stp" else "ap214")
                m = s2n.file_summary(os.path.join(d, name))
                self.assertTrue(m["valid"], name)
                self.assertEqual(m["faces"], cli["faces"], name)
                self.assertLessEqual(abs(m["area"] - cli["area"]), 1e-9 * cli["area"], name)
            with open(os.path.join(d, "a.stp")) as fh:
                self.assertIn("AP242", fh.read(2000).upper())
            with self.assertRaises(s2n.SettingsError):
                r.write(os.path.join(d, "a.obj"))
            with self.assertRaises(s2n.WriteError) as cm:
                r.write(os.path.join(d, "no", "such", "dir.step"))
            self.assertIn("dir.step", str(cm.exception))
            self.assertEqual(sorted(os.listdir(d)), ["a.brep", "a.iges", "a.step", "a.stp", "cli.step"])

    def test_tiny_parts_read_back_as_solids_or_are_refused(self):
        """#32 item 1: boxes at and below OCCT's precision (1e-7) written as STEP and read back by
        OCCT's STEPControl_Reader are valid solids of positive volume, or the STEP is refused
        (CageError naming the part, no file) after a warning about the part (tiny_part: smaller
        than 10 B-rep tolerances; thin_part / flat_part: thinner). The BREP is always written and
        reads back valid with the volume of the affine image of the unit cube's limit (Catmull-Clark
        is affine invariant: the volume scales by the product of the sides)."""
        v, f = cube_cage()
        f = np.array(f)
        scaled = lambda s: v * np.array(s)
        cages = {
            "unit cube and a 1e-12 cube": ((1, 1, 1), (np.vstack([v, scaled(1e-12) + [3, 0, 0]]), np.vstack([f, f + 8]))),
            "1 x 1e-9 x 1 box": ((1, 1e-9, 1), (scaled((1, 1e-9, 1)), f)),
            "1e8 x 1e-8 x 1 box": ((1e8, 1e-8, 1), (scaled((1e8, 1e-8, 1)), f)),
            "cube of size 2e-6": ((2e-6, 2e-6, 2e-6), (scaled(2e-6), f)),
        }
        unit = s2n.convert(s2n.Cage(v, f.tolist()))
        with tempfile.TemporaryDirectory() as d:
            unit.write(os.path.join(d, "u.brep"))
            unit_volume = s2n.file_summary(os.path.join(d, "u.brep"))["volume"]
        self.assertGreater(unit_volume, 0)
        self.assertLess(unit_volume, 8)  # inside the cage's hull
        warned, refused = {}, {}
        for name, (sides, (pv, pf)) in cages.items():
            r = s2n.convert(s2n.Cage(pv, pf.tolist()))
            warned[name] = [d["code"] for d in r.diagnostics if d["code"] in ("tiny_part", "thin_part", "flat_part")]
            with tempfile.TemporaryDirectory() as d:
                path = os.path.join(d, "t.step")
                try:
                    r.write(path)
                    m = s2n.file_summary(path)
                    self.assertTrue(m["valid"] and m["volume"] > 0, "%s: %s" % (name, m["check_message"]))
                    refused[name] = False
                except s2n.CageError as e:
                    self.assertIn("a STEP or IGES file cannot carry it", str(e))
                    self.assertEqual(os.listdir(d), [])
                    refused[name] = True
                r.write(os.path.join(d, "t.brep"))
                m = s2n.file_summary(os.path.join(d, "t.brep"))
            self.assertTrue(m["valid"], name)
            expected = unit_volume * sides[0] * sides[1] * sides[2] + (unit_volume * 1e-36 if "1e-12" in name else 0)
            self.assertAlmostEqual(m["volume"] / expected, 1, delta=1e-3, msg=name)
            self.assertEqual(refused[name], bool(warned[name]), name)
        self.assertEqual(warned["unit cube and a 1e-12 cube"], ["tiny_part"])
        self.assertEqual(warned["1 x 1e-9 x 1 box"], ["thin_part"])
        self.assertEqual(warned["1e8 x 1e-8 x 1 box"], ["flat_part"])
        self.assertEqual(warned["cube of size 2e-6"], [])

    def test_a_flat_closed_part_is_named(self):
        """#32: a cube flattened onto a plane converts to a closed B-rep of zero volume; the
        conversion warns (flat_part). The unit cube and a 1 x 1e-9 x 1 box get no such warning."""
        v, f = cube_cage()
        flat = s2n.convert(s2n.Cage(v * [1, 1, 0], f), allow_invalid=True)
        warned = [d["message"] for d in flat.diagnostics if d["code"] == "flat_part"]
        self.assertEqual(len(warned), 1)
        self.assertIn("face 0 (6 faces) encloses no volume", warned[0])
        self.assertTrue(any("encloses no volume" in w for w in flat.warnings))
        self.assertTrue(any("encloses no volume" in w for w in flat.report["warnings"]))
        for cage in (s2n.Cage(v, f), s2n.Cage(v * [1, 1e-9, 1], f)):
            self.assertEqual([d for d in s2n.convert(cage).diagnostics if d["code"] == "flat_part"], [])


class BoundTypes(unittest.TestCase):
    """The compiled part's bound types (issue #15): the settings as one object checked by the
    converter's rules, the result keeping the converter's own data (the OCCT shape, the patches
    and the cage they came from)."""

    def test_settings_object_maps_the_keywords_onto_the_converters_settings(self):
        st = s2n._subd2nurbs.Settings(level=2, faces="per-quad", preview="zebra", preview_samples=4, max_memory="1G")
        self.assertEqual((st.level, st.tolerance, st.faces, st.preview, st.preview_samples, st.fit),
                         (2, None, "per-quad", "zebra", 4, "approximate"))
        self.assertEqual(st.max_memory, 1024.0 ** 3)
        with self.assertRaises(TypeError):
            s2n._subd2nurbs.Settings(colour="red")
        # The converter's rule text, the same error as convert() raises.
        with self.assertRaises(s2n.SettingsError) as e:
            s2n._subd2nurbs.Settings(radial_steps=3)
        self.assertEqual((e.exception.setting, e.exception.rule, str(e.exception)),
                         ("radial_steps", "must be 1 or 2", "radial_steps must be 1 or 2"))

    def test_write_and_brep_text_come_from_the_kept_shape(self):
        r = s2n.convert(s2n.read_cage(corpus("catmark_cube_creases0")))
        text = r.brep_text
        self.assertIs(r.brep_text, text)  # made once, on first use
        self.assertEqual(s2n.brep_summary(text)["faces"], r.brep["faces"])
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "a.brep")
            r.write(path)
            with open(path) as fh:  # OCCT's BREP file is its BREP text behind the drawable header
                self.assertEqual(fh.read(), "DBRep_DrawableShape\n" + text)
        no_brep = s2n.convert(s2n.read_cage(corpus("catmark_cube_creases0")), brep=False)
        self.assertIsNone(no_brep.brep_text)
        with self.assertRaises(s2n.ConversionError):
            no_brep.write(os.path.join(tempfile.gettempdir(), "never.step"))

    def test_schema_rule_is_the_converters(self):
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        r = s2n.convert(s2n.read_cage(corpus("catmark_cube")))
        with tempfile.TemporaryDirectory() as d:
            with self.assertRaises(s2n.SettingsError) as e:
                r.write(os.path.join(d, "a.step"), schema="ap999")
            self.assertEqual((e.exception.setting, e.exception.rule), ("schema", "must be ap214 or ap242"))
            cli = subprocess.run([CLI, "convert", corpus("catmark_cube"), "-o", os.path.join(d, "b.step"),
                                  "--schema", "ap999"], capture_output=True, text=True)
            self.assertEqual(cli.stderr, "subd2nurbs: error: --%s %s\n" % (e.exception.setting, e.exception.rule))
            self.assertEqual(os.listdir(d), [])

    def test_cage_options_follow_the_converters_rule_on_every_path(self):
        """boundary, crease_method and triangles have one rule, the converter's (issue #15): the
        Cage, the arrays handed to the compiled module (no silent default for an unknown name)
        and the workbench (tests/freecad) refuse a name with the same SettingsError."""
        v, f = cube_cage()
        cage = s2n.Cage(v, f)
        for setting, documented in (("boundary", "must be none, edge-only or edge-and-corner"),
                                    ("crease_method", "must be uniform or chaikin"),
                                    ("triangles", "must be catmark or smooth")):
            with self.subTest(setting=setting):
                with self.assertRaises(s2n.SettingsError) as e:
                    s2n.Cage(v, f, **{setting: "sometimes"})
                self.assertEqual((e.exception.setting, e.exception.rule), (setting, documented))
                self.assertEqual(str(e.exception), "%s %s" % (setting, documented))
                # Every name the rule lists is taken (and kept as given).
                for name in s2n.CAGE_OPTIONS[setting]:
                    self.assertEqual(s2n.Cage(v, f, **{setting: name}).options[setting], name)
                # The compiled module's own entry points: the same error, not the default.
                args = list(cage._args())
                args[-1] = dict(cage.options, **{setting: "sometimes"})
                for entry in (s2n._subd2nurbs.info, s2n._subd2nurbs.validate):
                    with self.assertRaises(s2n.SettingsError) as direct:
                        entry(*args)
                    self.assertEqual((direct.exception.setting, direct.exception.rule), (setting, documented))
                with self.assertRaises(s2n.SettingsError) as typed:
                    s2n.Cage(v, f, **{setting: 1})
                self.assertEqual(typed.exception.setting, setting)

    def test_polar_mode_takes_the_command_lines_names_with_its_rule(self):
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        cage_file = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples",
                                 "capped_cylinder.obj")  # two polar structures
        cage = s2n.read_cage(cage_file)
        # "off" is Catmull-Clark (as polar=False), not a truthy string.
        for name, flag in (("on", True), ("off", False)):
            by_name = s2n.convert(cage, brep=False, polar=name)
            by_flag = s2n.convert(cage, brep=False, polar=flag)
            self.assertEqual({k: x for k, x in by_name.report.items() if not k.endswith("_ms")},
                             {k: x for k, x in by_flag.report.items() if not k.endswith("_ms")})
        self.assertEqual(len(s2n.convert(cage, brep=False, polar="on").report["polar"]["caps"]), 2)
        self.assertEqual(len(s2n.convert(cage, brep=False, polar="off").report["polar"]["caps"]), 0)
        with self.assertRaises(s2n.SettingsError) as e:
            s2n.convert(cage, brep=False, polar="maybe")
        self.assertEqual((e.exception.setting, e.exception.rule), ("polar", "must be on or off"))
        with tempfile.TemporaryDirectory() as d:
            for command in ("convert", "refine"):
                out = os.path.join(d, "a.step" if command == "convert" else "a.obj")
                cli = subprocess.run([CLI, command, cage_file, "-o", out, "--polar", "maybe"],
                                     capture_output=True, text=True)
                self.assertEqual(cli.returncode, 1)
                self.assertEqual(cli.stderr, "subd2nurbs: error: --polar %s\n" % e.exception.rule)

    def test_make_preview_is_the_preview_stage_without_a_second_conversion(self):
        cage = s2n.read_cage(corpus("catmark_cube_creases0"))
        r = s2n.convert(cage, level=1)
        for color in ("curvature", "deviation", "zebra"):
            later = r.make_preview(color, 5)
            direct = s2n.convert(cage, level=1, brep=False, preview=color, preview_samples=5)
            self.assertEqual(later["color"], color)
            for key in ("positions", "normals", "colors", "values", "triangles"):
                np.testing.assert_array_equal(later[key], direct.preview[key], key)
            self.assertEqual((later["value_min"], later["value_max"]),
                             (direct.preview["value_min"], direct.preview["value_max"]))
        # 5 x 5 points per patch: the preview's own grid, not the conversion's.
        self.assertEqual(len(r.make_preview("zebra", 5)["positions"]), 25 * r.report["patches"]["total"])
        with self.assertRaises(s2n.SettingsError) as e:
            r.make_preview("zebra", 65)
        self.assertEqual((e.exception.setting, e.exception.rule), ("preview_samples", "must be 2 .. 64"))
        with self.assertRaises(s2n.SettingsError) as e:
            r.make_preview("rainbow", 5)
        self.assertEqual(e.exception.setting, "preview")

    def test_preview_is_a_stage_of_the_conversion(self):
        keys = []
        s2n.convert(s2n.read_cage(corpus("catmark_cube")), brep=False, preview="zebra",
                    progress=lambda stage, fraction: keys.append(stage.key))
        self.assertEqual(keys[-1], "preview")


class SettingsTable(unittest.TestCase):
    """convert()'s keywords come from the converter's settings table (subd2nurbs.SETTINGS,
    docs/settings.md): every row is a keyword with its default, its type checked and its help
    in the docstring; a row added to the package's table is checked by the same loop."""

    def test_every_row_is_a_keyword_with_its_default_and_doc(self):
        names = [row["name"] for row in s2n.SETTINGS]
        self.assertIn("level", names)
        self.assertIn("max_memory", names)
        defaults = s2n._subd2nurbs.Settings()
        cage = s2n.read_cage(corpus("catmark_cube"))
        for row in s2n.SETTINGS:
            with self.subTest(setting=row["name"]):
                self.assertEqual(getattr(defaults, row["name"]), row["default"])
                self.assertIn("    %s: %s" % (row["name"], row["help"]), s2n.convert.__doc__)
                if row["type"] in ("flag", "on-off"):
                    continue
                with self.assertRaises(s2n.SettingsError) as e:  # a list is no value of any type
                    s2n.convert(cage, brep=False, **{row["name"]: [1]})
                self.assertEqual(e.exception.setting, row["name"])
        with self.assertRaises(TypeError):
            s2n.convert(cage, colour="red")

    def test_every_kind_of_error_has_its_exception_class(self):
        from subd2nurbs import errors
        kinds = s2n._subd2nurbs.error_classes()
        self.assertEqual([k[0] for k in kinds], ["usage", "settings", "resources", "input", "fit", "write", "export"])
        for name, code, cls in kinds:
            with self.subTest(kind=name):
                self.assertTrue(issubclass(getattr(errors, cls), errors.Subd2NurbsError))
                self.assertIn(code, (1, 2, 3, 4))

    def test_a_row_added_to_the_table_is_checked_by_the_loop(self):
        row = {"name": "dummy_setting", "type": "integer", "default": 5, "default_text": "", "help": "a test row",
               "choices": [], "cli": None, "python": True, "property": None}
        self.assertEqual(s2n._setting_value(row, 7), 7)
        with self.assertRaises(s2n.SettingsError) as e:
            s2n._setting_value(row, "seven")
        self.assertEqual((e.exception.setting, e.exception.rule), ("dummy_setting", "must be an integer"))


def _without_timings(report):
    return {k: x for k, x in report.items() if not k.endswith("_ms")}


class Threads(unittest.TestCase):
    """#32 item 5: convert runs without the interpreter lock, so threads convert in parallel
    with the results of sequential runs; the progress callback still runs in Python."""

    NAMES = ("catmark_cube_creases0", "catmark_nonquads", "catmark_torus", "catmark_pyramid")

    def test_threads_give_the_sequential_results(self):
        from concurrent.futures import ThreadPoolExecutor
        cages = [s2n.read_obj(corpus(n)) for n in self.NAMES]
        sequential = [s2n.convert(c) for c in cages]
        with ThreadPoolExecutor(4) as pool:
            threaded = list(pool.map(s2n.convert, cages))
        for name, a, b in zip(self.NAMES, sequential, threaded):
            self.assertEqual(a.brep_text, b.brep_text, name)
            self.assertEqual(_without_timings(a.report), _without_timings(b.report), name)

    def test_other_threads_run_during_a_conversion(self):
        """Another Python thread keeps running while a conversion runs: its longest pause is a
        small part of the conversion's time (with the lock held it was all of it: 2.3 of 2.3 s
        for catmark_car)."""
        import threading
        import time
        pause = [0.0]
        stop = threading.Event()

        def spin():
            last = time.perf_counter()
            while not stop.is_set():
                now = time.perf_counter()
                pause[0] = max(pause[0], now - last)
                last = now

        cage = s2n.read_obj(corpus("catmark_car"))
        s2n.convert(cage, level=0)  # OCCT's first-use initialisation, outside the measurement
        t = threading.Thread(target=spin)
        t.start()
        try:
            time.sleep(0.05)
            pause[0] = 0.0
            start = time.perf_counter()
            s2n.convert(cage, level=1)
            elapsed = time.perf_counter() - start
        finally:
            stop.set()
            t.join()
        self.assertLess(pause[0], 0.5 * elapsed, "paused %.3f s of %.3f s" % (pause[0], elapsed))

    def test_progress_and_errors_from_a_thread(self):
        from concurrent.futures import ThreadPoolExecutor
        stages = []
        with ThreadPoolExecutor(2) as pool:
            done = pool.submit(s2n.convert, s2n.read_obj(corpus("catmark_cube")),
                               progress=lambda s, x: stages.append((s.key, x)))
            v, f = cube_cage()
            flipped = [list(reversed(f[0]))] + f[1:]  # raised by the core, without the lock
            bad = pool.submit(s2n.convert, s2n.Cage(v, flipped))
            done.result()
            with self.assertRaises(s2n.CageError) as e:
                bad.result()
            self.assertEqual(e.exception.code, "inconsistent-orientation")
        self.assertEqual({k for k, _ in stages} - {"fit"}, {"patches", "deviation", "packing", "continuity", "brep"})
        self.assertEqual(max(x for k, x in stages if k == "brep"), 1.0)


class Versions(unittest.TestCase):
    def test_occt_version(self):
        self.assertRegex(s2n.OCC_VERSION, r"^\d+\.\d+\.\d+")
        self.assertTrue(s2n.occt_compatible(s2n.OCC_VERSION))
        self.assertFalse(s2n.occt_compatible("7.5.0"))


class Fitting(unittest.TestCase):
    """convert(fit="interpolate"[, fair=W]) and fair(): the limit surface through the vertices."""

    def test_interpolating_patches_pass_through_the_vertices(self):
        # A regular torus: every patch is a bicubic B-spline whose corners are limit points, so
        # the patch corners (clamped: the corner poles) must be cage vertices after the fit, and
        # not before.
        cage = s2n.read_cage(corpus("catmark_torus"))
        size = float(np.linalg.norm(cage.vertices.max(0) - cage.vertices.min(0)))

        def miss(result):
            corners = np.concatenate([p["poles"][[0, 0, -1, -1], [0, -1, 0, -1]] for p in result.patches])
            d = np.linalg.norm(cage.vertices[None, :, :] - corners[:, None, :], axis=2).min(axis=0)
            return d.max() / size

        plain = s2n.convert(cage, brep=False, faces="per-quad")
        fitted = s2n.convert(cage, fit="interpolate", brep=False, faces="per-quad")
        self.assertGreater(miss(plain), 1e-2)
        self.assertLess(miss(fitted), 1e-12)
        f = fitted.report["fit"]
        self.assertEqual(f["mode"], "interpolate")
        self.assertLess(f["residual"]["max_relative"], 1e-12)
        self.assertEqual(fitted.cage_vertices.shape, cage.vertices.shape)
        self.assertIsNone(plain.report["fit"]["residual"])

    def test_fair_fit_and_errors(self):
        cage = s2n.read_cage(corpus("catmark_val2_back2back"))
        with self.assertRaises(s2n.FitError) as e:
            s2n.convert(cage, fit="interpolate", brep=False)
        self.assertEqual(sorted(e.exception.vertices), [0, 1, 2])
        r = s2n.convert(cage, fit="interpolate", fair=0.01, brep=False)
        self.assertEqual(r.report["fit"]["fair_weight"], 0.01)
        for bad in ({"fair": 1.0}, {"fit": "interpolate", "fair": 0}, {"fit": "interpolate", "fair": -1},
                    {"fit": "exact"}):
            with self.assertRaises(s2n.SettingsError):
                s2n.convert(cage, brep=False, **bad)

    def test_fair_keeps_vertices_bit_for_bit(self):
        cage = s2n.read_cage(corpus("catmark_fvar_bound2"))
        faired, info = s2n.fair(cage, weight=0.5, keep="boundary")
        self.assertLess(info["energy_after"], info["energy_before"])
        self.assertGreater(info["kept"], 0)
        moved = np.any(faired.vertices != cage.vertices, axis=1)
        self.assertEqual(int((~moved).sum()) >= info["kept"], True)
        self.assertTrue(moved.any())
        self.assertEqual(faired.creases, cage.creases)
        with self.assertRaises(s2n.SettingsError):
            s2n.fair(cage, weight=0)
        # The fairing's rules are the converter's: the CLI prints the same rule after its option.
        self.assertTrue(CLI, "SUBD2NURBS_CLI (the subd2nurbs executable) is not set")
        for kwargs, option, rule in (({"weight": -1.0}, ["--weight=-1"], "must be a positive number"),
                                     ({"levels": 5}, ["--levels", "5"], "must be 0 .. 4"),
                                     ({"membrane": -1.0}, ["--membrane=-1"], "must be a number >= 0"),
                                     ({"keep": "nothing"}, ["--keep", "nothing"], "must be boundary, creases or tagged")):
            with self.assertRaises(s2n.SettingsError) as e:
                s2n.fair(cage, **kwargs)
            setting = next(iter(kwargs))
            self.assertEqual((e.exception.setting, e.exception.rule), (setting, rule))
            with tempfile.TemporaryDirectory() as d:
                r = subprocess.run([CLI, "fair", corpus("catmark_cube"), "-o", os.path.join(d, "f.obj")] + option,
                                   capture_output=True, text=True)
            self.assertEqual((r.returncode, r.stderr), (1, "subd2nurbs: error: --%s %s\n" % (setting, rule)))


def torus_cage(m=8, n=6, R=3.0, r=1.0):
    """The stretched, bent torus of the C++ shape fit tests (tests/fit/shape_fit_test_util.h)."""
    v = []
    for i in range(m):
        for j in range(n):
            a, b = 2 * math.pi * i / m, 2 * math.pi * j / n
            v.append((1.4 * (R + r * math.cos(b)) * math.cos(a), (R + r * math.cos(b)) * math.sin(a),
                      r * math.sin(b) + 0.5 * math.cos(a) ** 2))
    faces = [[i * n + j, (i + 1) % m * n + j, (i + 1) % m * n + (j + 1) % n, i * n + (j + 1) % n]
             for i in range(m) for j in range(n)]
    return s2n.Cage(v, faces, creases=[(i * n, (i + 1) % m * n, 1.0) for i in range(m)], name="torus")


class ShapeFitTest(unittest.TestCase):
    def two_sided(self, d):
        return max(d["limit_to_target"]["max"], d["target_to_limit"]["max"])

    def test_convert_fit_to_is_fit_then_convert(self):
        truth = torus_cage()
        fine = s2n.refine(truth, 2)
        rng = np.random.default_rng(5)
        start = s2n.Cage(truth.vertices + rng.uniform(-0.02, 0.02, truth.vertices.shape), truth.faces, truth.creases)
        one = s2n.convert(start, fit_to=fine, brep=False)
        two = s2n.convert(s2n.fit(start, fine)[0], brep=False)
        plain = s2n.convert(start, brep=False)
        for a, b, c in zip(one.patches, two.patches, plain.patches):
            np.testing.assert_array_equal(a["poles"], b["poles"])
        self.assertFalse(all(np.array_equal(a["poles"], c["poles"]) for a, c in zip(one.patches, plain.patches)))
        with self.assertRaises(s2n.SettingsError) as e:
            s2n.convert(start, fit_to=fine, fit="interpolate")
        self.assertEqual(e.exception.setting, "fit_to")

    def test_fit_brings_a_perturbed_torus_back(self):
        truth = torus_cage()
        # The target: the true cage refined three times (close to its limit), as a Cage, as
        # points with triangles, and as a file.
        fine = s2n.refine(truth, 3)
        rng = np.random.default_rng(3)
        diag = np.linalg.norm(truth.vertices.max(0) - truth.vertices.min(0))
        moved = truth.vertices + rng.uniform(-0.01, 0.01, truth.vertices.shape) * diag
        start = s2n.Cage(moved, truth.faces, truth.creases, name="perturbed")
        fitted, info = s2n.fit(start, fine, max_iterations=10)
        before, after = self.two_sided(info["before"]), self.two_sided(info["after"])
        print("fit: two-sided max before %.3g, after %.3g, %d iterations (%s)" % (before, after, info["iterations"], info["stop"]))
        self.assertLess(after, 0.3 * before)
        self.assertGreater(info["iterations"], 0)
        self.assertIn(info["stop"], ("tolerance", "converged", "iteration limit"))
        self.assertEqual(fitted.faces, truth.faces)
        self.assertEqual(fitted.creases, truth.creases)
        self.assertFalse(np.array_equal(fitted.vertices, start.vertices))
        tris = np.array([[f[0], f[k], f[k + 1]] for f in fine.faces for k in (1, 2)])
        _, info2 = s2n.fit(start, fine.vertices, triangles=tris, max_iterations=10)
        self.assertAlmostEqual(self.two_sided(info2["after"]), after, delta=1e-12)
        _, cloud = s2n.fit(start, fine.vertices, max_iterations=3)
        self.assertLess(cloud["after"]["target_to_limit"]["max"], cloud["before"]["target_to_limit"]["max"])
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "target.xyz")
            np.savetxt(path, fine.vertices)
            _, from_file = s2n.fit(start, path, max_iterations=3)
            self.assertEqual(from_file["before"], cloud["before"])
            with self.assertRaises(s2n.CageError):
                s2n.fit(start, os.path.join(d, "missing.ply"))

    def test_exact_target_recovers_the_cage(self):
        """exact_target=True (as `fit --exact-target`): a perturbed torus cage (no creases: every
        refined vertex regular) fitted to exact limit points of the true cage comes back to the
        true cage. Oracle: the limit points are the level-3 vertices pushed to the limit with
        the regular Catmull-Clark limit mask (16 v + 4 sum of edge neighbours + sum of diagonal
        neighbours) / 36."""
        t = torus_cage()
        truth = s2n.Cage(t.vertices, t.faces, name="torus")
        fine = s2n.refine(truth, 3)
        v = np.asarray(fine.vertices, float)
        acc = 16 * v.copy()
        for f in fine.faces:  # each edge neighbour is in two of the vertex's faces
            for k in range(4):
                acc[f[k]] += 2 * (v[f[(k + 1) % 4]] + v[f[(k + 3) % 4]]) + v[f[(k + 2) % 4]]
        limit = acc / 36
        tris = np.array([[f[0], f[k], f[k + 1]] for f in fine.faces for k in (1, 2)])
        diag = np.linalg.norm(truth.vertices.max(0) - truth.vertices.min(0))
        rng = np.random.default_rng(3)
        start = s2n.Cage(truth.vertices + rng.uniform(-0.01, 0.01, truth.vertices.shape) * diag, truth.faces)
        errors = {}
        for exact in (False, True):
            fitted, info = s2n.fit(start, limit, triangles=tris, exact_target=exact)
            errors[exact] = np.abs(fitted.vertices - truth.vertices).max() / diag
        print("fit: cage error (relative) default %.3g, exact_target %.3g" % (errors[False], errors[True]))
        self.assertLess(errors[True], 1e-5)
        self.assertGreater(errors[False], 1e-4)  # the flag is what makes the difference
        for bad in ({"min_gain": -1}, {"exact_target": "yes"}):
            with self.assertRaises(s2n.SettingsError) as e:
                s2n.fit(start, limit, **bad)
            self.assertEqual(e.exception.setting, next(iter(bad)))

    def test_fit_progress_and_cancel(self):
        truth = torus_cage()
        fine = s2n.refine(truth, 3)
        rng = np.random.default_rng(5)
        diag = np.linalg.norm(truth.vertices.max(0) - truth.vertices.min(0))
        start = s2n.Cage(truth.vertices + rng.uniform(-0.01, 0.01, truth.vertices.shape) * diag, truth.faces,
                         truth.creases)
        calls = []
        _, full = s2n.fit(start, fine, max_iterations=6, progress=lambda i, n, obj: calls.append((i, n, obj)))
        # one call per pairing that a solve follows, in order, with the cap and the objective
        self.assertEqual([c[0] for c in calls], list(range(full["iterations"])))
        self.assertTrue(all(c[1] == 6 for c in calls))
        self.assertEqual([c[2] for c in calls], [h["objective"] for h in full["history"][:len(calls)]])
        # returning False after the second pairing: two solves, stop "cancelled", the second solve's cage
        cancelled, info = s2n.fit(start, fine, max_iterations=6, progress=lambda i, n, obj: i < 1)
        self.assertEqual(info["stop"], "cancelled")
        self.assertEqual(info["iterations"], 1)
        two, _ = s2n.fit(start, fine, max_iterations=1)
        np.testing.assert_array_equal(cancelled.vertices, two.vertices)
        with self.assertRaises(s2n.SettingsError) as e:
            s2n.fit(start, fine, progress=3)
        self.assertEqual(e.exception.setting, "progress")

    def test_fit_argument_errors(self):
        cage = torus_cage()
        points = cage.vertices
        for kwargs, setting in (({"smoothing": "x"}, "smoothing"), ({"levels": 2.5}, "levels"),
                                ({"max_iterations": "10"}, "max_iterations"), ({"tolerance": True}, "tolerance"),
                                ({"smoothing": -1.0}, "smoothing"), ({"levels": 5}, "levels"),
                                ({"max_iterations": 0}, "max_iterations"), ({"tolerance": 0.0}, "tolerance"),
                                ({"triangles": [[0, 1]]}, "triangles"), ({"triangles": [[0, 1, 999]]}, "triangles")):
            with self.assertRaises(s2n.SettingsError) as e:
                s2n.fit(cage, points, **kwargs)
            self.assertEqual(e.exception.setting, setting)
        for target in (42, [[0.0, 0.0, 0.0]], np.zeros((4, 2)), np.zeros((0, 3))):
            with self.assertRaises(s2n.SettingsError) as e:
                s2n.fit(cage, target)
            self.assertEqual(e.exception.setting, "target")
        with self.assertRaises(TypeError):
            s2n.fit("not a cage", points)


MESH_DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "mesh")


def euler_characteristic(face_lists, num_vertices):
    edges = {tuple(sorted((f[i], f[(i + 1) % len(f)]))) for f in face_lists for i in range(len(f))}
    return num_vertices - len(edges) + len(face_lists)


class MeshPath(unittest.TestCase):
    """The mesh path (issue #28, docs/meshes.md) from Python: the road rule, read_mesh, convert's
    remeshed cage. Oracles: the mesh's own topology (Euler characteristic counted here), the rule
    on shapes whose answer is known (a triangulated quad cube, a tetrahedron, a dense mesh)."""

    def test_road_rule(self):
        v, faces = cube_cage()
        tris = [[f[0], f[1], f[2]] for f in faces] + [[f[0], f[2], f[3]] for f in faces]
        self.assertEqual(s2n.input_route(s2n.Cage(v, faces))["kind"], "cage")  # quads
        self.assertEqual(s2n.input_route(s2n.Cage(v, tris))["kind"], "cage")   # they pair back
        self.assertEqual(s2n.input_route(s2n.Cage(v, tris), input="mesh")["kind"], "mesh")
        tet = s2n.Cage(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float),
                       [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        self.assertEqual(s2n.input_route(tet)["kind"], "cage")  # 4 triangles: a triangle cage
        mesh = s2n.read_cage(os.path.join(MESH_DATA, "plate_holes.STL"))
        self.assertEqual(mesh.route["kind"], "mesh", mesh.route)
        self.assertTrue(all(n == 3 for n in mesh.face_sizes))
        self.assertIsNone(mesh.quad_recovery)
        with self.assertRaises(s2n.SettingsError):
            s2n.input_route(tet, input="sometimes")

    def test_convert_a_mesh(self):
        mesh = s2n.read_mesh(os.path.join(MESH_DATA, "plate_holes.STL"))
        result = s2n.convert(mesh, target_faces=300)
        cage = result.made_cage
        self.assertIsNotNone(cage)
        self.assertTrue(all(n == 4 for n in cage.face_sizes))
        self.assertEqual(euler_characteristic(cage.faces, cage.num_vertices),
                         euler_characteristic(mesh.faces, mesh.num_vertices))
        m = result.report["mesh"]
        self.assertEqual(m["cage"]["faces"], cage.num_faces)
        self.assertEqual(m["input_triangles"], mesh.num_faces)
        self.assertTrue(result.brep["valid"])
        self.assertTrue(result.brep["is_solid"])
        self.assertEqual(len(cage.creases), m["cage"]["feature_edges"])
        # The cage converted is the made cage: its vertices are the result's cage vertices.
        np.testing.assert_array_equal(cage.vertices, result.cage_vertices)
        # A given size is obeyed: one round, whatever fit_tolerance (docs/meshes.md "Size chosen by
        # the fit tolerance"); the keyword's rule is checked before any work.
        self.assertEqual(m["size"]["rule"], "given")
        self.assertEqual([r["target_faces"] for r in m["size"]["rounds"]], [300])
        # A cancel inside the remesh or the fit (the mesh stage's fractions) stops there.
        fractions = []

        def progress(stage, fraction):
            if stage.key == "mesh" and fraction > 0:
                fractions.append(fraction)
                return False if fraction >= 0.5 else None
            self.assertEqual(stage.key, "mesh")  # no later stage runs
        with self.assertRaises(s2n.Cancelled):
            s2n.convert(mesh, target_faces=300, progress=progress)
        self.assertGreaterEqual(fractions[-1], 0.5)
        self.assertTrue(all(f < 0.5 for f in fractions[:-1]))
        with self.assertRaises(s2n.SettingsError) as e:
            s2n.convert(mesh, fit_tolerance=-1e-3)
        self.assertIn("fit_tolerance", str(e.exception))
        # A quad cage given with input="mesh" is remeshed too; with input="cage" it is not.
        v, faces = cube_cage()
        self.assertIsNone(s2n.convert(s2n.Cage(v, faces), input="cage").made_cage)


if __name__ == "__main__":
    unittest.main()
