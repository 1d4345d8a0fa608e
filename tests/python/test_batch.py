"""subd2nurbs.batch (issue #30): a library converted file by file, each in a process of its own.

Oracles: the corpus' known non-manifold shapes (tests/common/corpus.h) fail with the exit code of
invalid input and every other shape converts; hand-made hostile files fail with the exit codes
docs (subd2nurbs --help) gives them; a converted file is byte-identical to a plain
`subd2nurbs convert` of the same file (SOURCE_DATE_EPOCH fixes the STEP time stamp) and its
summary row holds the numbers of that run's report; a converter that hangs is killed at the time
limit (its process is gone afterwards); an interrupted run resumed converts exactly the files the
first one had not finished and ends with the outputs of an uninterrupted run (local pool and
Dask); a real Dask cluster (2 workers on 127.0.0.1 in working folders of their own, without
SOURCE_DATE_EPOCH: the batch passes it on) gives the local pool's bytes and rows, reading the
shared path or with the inputs sent as bytes (the converter's log on the workers: temporary
copies only), also after losing a worker; IGES and BREP files are byte-identical for 1 and 2
workers, the cluster and a plain convert, the IGES dates those of SOURCE_DATE_EPOCH.

Environment: SUBD2NURBS_CLI (the command line), SUBD2NURBS_CORPUS_DIR, PYTHONPATH (build/python).
"""
import csv
import filecmp
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

from subd2nurbs import batch

CLI = os.environ["SUBD2NURBS_CLI"]
CORPUS = os.environ["SUBD2NURBS_CORPUS_DIR"]
HERE = os.path.dirname(os.path.abspath(__file__))
EPOCH = "1700000000"
# Cheap settings for the many runs of the tests: the coarsest level, B-rep and report as usual.
FAST = {"level": 0}


def non_manifold_shapes():
    """The corpus shapes the converter must refuse as invalid input (tests/common/corpus.h)."""
    with open(os.path.join(HERE, "..", "common", "corpus.h"), encoding="utf-8") as f:
        names = re.findall(r'\{"(catmark_\w+)", MeshErrorCode::', f.read())
    assert len(names) >= 5, names
    return set(names)


# Hostile files and the exit code `subd2nurbs --help` documents for them.
HOSTILE = {
    "hostile/empty.obj": ("", 2),
    "hostile/bad_index.obj": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 7\n", 2),
    "hostile/garbage.obj": ("v 0 zero 0\nf 1 2 3\n", 2),
    "hostile/nested/non_manifold.obj": (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 0 1 1\n"
        "f 1 2 3 4\nf 1 4 6 5\nf 1 4 3 2\n", 2),
    "hostile/binary.stl": ("\x00\x01\x02solid nonsense" * 3, 2),
}


def make_tree(root):
    """root/corpus/*.obj (the 87 shapes) and root/hostile/... (HOSTILE)."""
    shutil.copytree(CORPUS, os.path.join(root, "corpus"), ignore=shutil.ignore_patterns("*.md", "*.txt"))
    for rel, (text, _) in HOSTILE.items():
        path = os.path.join(root, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="latin-1") as f:
            f.write(text)


def env():
    e = dict(os.environ, SOURCE_DATE_EPOCH=EPOCH)
    return e


def batch_command(*args):
    return [sys.executable, "-m", "subd2nurbs.batch", "--cli", CLI] + list(args)


def stable(row):
    """A summary row without what differs between runs: times, memory, where the input tree lies
    (also in the messages)."""
    rel = os.path.splitext(row["output"])[0] + os.path.splitext(row["input"])[1]  # ROOT/rel is the input
    root = row["input"][:len(row["input"]) - len(rel)]
    out = {k: v for k, v in row.items() if k not in ("time_s", "cpu_s", "peak_memory_mb", "input")}
    out["message"] = out["message"].replace(root, "ROOT/")[:300]  # cut at 500 characters with the root
    return out


def outputs(outdir):
    """Relative paths of the converted files (not reports, summaries or journals)."""
    found = []
    for folder, _, files in os.walk(outdir):
        for name in files:
            if name.endswith(".step"):
                found.append(os.path.relpath(os.path.join(folder, name), outdir))
    return sorted(found)


def wait_for(predicate, what, timeout=300):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError("gave up waiting for " + what)


def journal_lines(outdir):
    try:
        with open(os.path.join(outdir, batch.JOURNAL), encoding="utf-8") as f:
            return sum(1 for line in f if line.endswith("\n"))
    except OSError:
        return 0


def interrupt_after(test, args, out, files, timeout):
    """Runs the batch `args`, sends SIGINT once `files` files are in the journal of `out`, checks
    it ends with exit code 130 and an interrupted summary, and returns the outputs it left."""
    run = subprocess.Popen(args, env=env(), stderr=subprocess.DEVNULL)
    wait_for(lambda: journal_lines(out) >= files or run.poll() is not None, "%d files converted" % files)
    test.assertIsNone(run.poll(), "the batch ended before it was interrupted")
    run.send_signal(signal.SIGINT)
    test.assertEqual(run.wait(timeout=timeout), 130)
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        part = json.load(f)
    test.assertTrue(part["run"]["interrupted"])
    left = [r["output"] for r in part["files"] if r["status"] == "interrupted"]
    test.assertTrue(left)
    return left


def write_cube_gltf(path, bin_rel):
    """A unit cube as 12 triangles in a .gltf whose buffer is the external file `bin_rel`
    (relative to the .gltf, may go up: "../buffers/cube.bin")."""
    import struct
    v = [(x, y, z) for x in (0., 1.) for y in (0., 1.) for z in (0., 1.)]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    pos = b"".join(struct.pack("<3f", *p) for p in v)
    idx = b"".join(struct.pack("<3H", *t) for t in tris)
    doc = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
           "buffers": [{"uri": bin_rel, "byteLength": len(pos + idx)}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                           {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 1]},
                         {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]}
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(doc, f)
    buffer = os.path.normpath(os.path.join(os.path.dirname(path), bin_rel))
    os.makedirs(os.path.dirname(buffer), exist_ok=True)
    with open(buffer, "wb") as f:
        f.write(pos + idx)


# A converter that logs the input path it is given and the working directory, then is the real one.
LOGGING_CONVERTER = """#!/bin/sh
printf '%s\\t%s\\n' "$2" "$(pwd)" >> "{log}"
exec "{cli}" "$@"
"""


def logging_converter(folder):
    """(the converter's path, its log's path)."""
    log = os.path.join(folder, "inputs.log")
    fake = os.path.join(folder, "logging-subd2nurbs")
    with open(fake, "w", encoding="utf-8") as f:
        f.write(LOGGING_CONVERTER.replace("{log}", log).replace("{cli}", CLI))
    os.chmod(fake, 0o755)
    return fake, log


def report_without_times(path):
    """A convert report without what differs between runs of the same conversion: the times
    and where the output folder is."""
    with open(path, encoding="utf-8") as f:
        report = json.load(f)
    for key in ("timings_ms", "quality_ms", "quality_wait_ms", "output"):
        report.pop(key, None)
    return report


def same_bytes(a, b):
    with open(a, "rb") as fa, open(b, "rb") as fb:
        return fa.read() == fb.read()


SHARED = {}


def setUpModule():
    """One uninterrupted local run over corpus + hostile files, shared by the tests."""
    os.environ["SOURCE_DATE_EPOCH"] = EPOCH
    tmp = tempfile.mkdtemp(prefix="s2n-batch-")
    inputs = os.path.join(tmp, "in")
    make_tree(inputs)
    reference = os.path.join(tmp, "reference")
    summary = batch.run([inputs], reference, FAST, workers=2, cli=CLI, timeout=300)
    SHARED.update(tmp=tmp, inputs=inputs, reference=reference, summary=summary)


def tearDownModule():
    shutil.rmtree(SHARED["tmp"], ignore_errors=True)


class BatchTestCase(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        for key, value in SHARED.items():
            setattr(cls, key, value)

    def reference_json(self):
        with open(os.path.join(self.reference, "summary.json"), encoding="utf-8") as f:
            return json.load(f)


class LocalPool(BatchTestCase):
    def test_status_of_every_file(self):
        refused = non_manifold_shapes()
        rows = {r["output"]: r for r in self.summary.files}
        corpus = sorted(n for n in os.listdir(CORPUS) if n.endswith(".obj"))
        self.assertEqual(len(corpus), 87)
        self.assertEqual(len(rows), 87 + len(HOSTILE))
        for name in corpus:
            stem = name[:-4]
            row = rows[os.path.join("corpus", stem + ".step")]
            if stem in refused:
                self.assertEqual((row["status"], row["exit_code"]), ("invalid-input", 2), row)
                self.assertIn(name, row["message"])  # the message names the file
            else:
                self.assertEqual((row["status"], row["exit_code"]), ("ok", 0), row)
        for rel, (_, code) in HOSTILE.items():
            row = rows[os.path.splitext(rel)[0] + ".step"]
            self.assertEqual(row["exit_code"], code, row)
            self.assertEqual(row["status"], batch.EXIT_CLASSES[code], row)
            self.assertFalse(os.path.exists(os.path.join(self.reference, row["output"])), row)
        self.assertEqual(self.summary.counts, {"ok": 87 - len(refused), "invalid-input": len(refused) + len(HOSTILE)})

    def test_summary_files(self):
        data = self.reference_json()
        self.assertEqual(data["format"], "subd2nurbs-batch-summary")
        self.assertEqual([r["output"] for r in data["files"]], [r["output"] for r in self.summary.files])
        with open(os.path.join(self.reference, "summary.csv"), newline="", encoding="utf-8") as f:
            table = list(csv.DictReader(f))
        self.assertEqual(len(table), len(data["files"]))
        for line, row in zip(table, data["files"]):
            self.assertEqual(line["status"], row["status"])
            self.assertEqual(line["input_hash"], row["input_hash"])
            self.assertEqual(line["exit_code"], str(row["exit_code"]))
        # The hash is the input's SHA-256.
        import hashlib
        first = data["files"][0]
        with open(first["input"], "rb") as f:
            self.assertEqual(first["input_hash"], "sha256:" + hashlib.sha256(f.read()).hexdigest())

    def test_outputs_equal_plain_convert(self):
        """Mirrored tree; the output byte-identical to a plain `subd2nurbs convert` and the
        summary's numbers those of its report."""
        plain = os.path.join(self.tmp, "plain")
        os.makedirs(plain, exist_ok=True)
        for stem in ("catmark_cube", "catmark_torus", "catmark_pole8"):
            out, rep = os.path.join(plain, stem + ".step"), os.path.join(plain, stem + ".json")
            subprocess.run([CLI, "convert", os.path.join(CORPUS, stem + ".obj"), "-o", out, "--report", rep,
                            "-q", "--level", "0"], check=True, env=env())
            ours = os.path.join(self.reference, "corpus", stem + ".step")
            self.assertTrue(filecmp.cmp(out, ours, shallow=False), stem)
            with open(ours, encoding="utf-8") as f:  # SOURCE_DATE_EPOCH 1700000000, in UTC
                self.assertIn("'2023-11-14T22:13:20'", f.read(1000))
            with open(rep, encoding="utf-8") as f:
                report = json.load(f)
            row = next(r for r in self.summary.files if r["output"] == os.path.join("corpus", stem + ".step"))
            self.assertEqual(row["faces"], report["faces"]["total"])
            self.assertEqual(row["poles"], report["faces"]["poles"])
            self.assertEqual(row["deviation"], report["deviation"]["max"])
            self.assertEqual(row["g1_angle_deg"], report["continuity"]["max_normal_angle_deg"])
            self.assertGreater(row["peak_memory_mb"], 1)
            self.assertTrue(os.path.exists(os.path.join(self.reference, row["report"])))

    def test_resume_skips_unchanged(self):
        """A second run into a copy converts nothing and has the same rows; per-file settings of
        a manifest; --retry-failed converts again exactly the files that failed."""
        again = os.path.join(self.tmp, "again")
        shutil.copytree(self.reference, again)
        s = batch.run([self.inputs], again, FAST, workers=2, cli=CLI)
        self.assertEqual((s.converted, s.skipped), (0, len(s.files)))
        self.assertEqual([stable(r) for r in s.files], [stable(r) for r in self.summary.files])
        # Another setting: every file again (here only two files, through a manifest).
        manifest = os.path.join(self.inputs, "two.csv")
        with open(manifest, "w", encoding="utf-8") as f:
            f.write("input,output,level,max_faces\ncorpus/catmark_cube.obj,,,\n"
                    "corpus/catmark_torus.obj,torus_small.step,1,10\n")
        m = batch.run([], os.path.join(self.tmp, "manifest"), FAST, manifest=manifest, workers=2, cli=CLI)
        rows = {r["output"]: r for r in m.files}
        self.assertEqual(rows["corpus/catmark_cube.step"]["status"], "ok")
        # max_faces 10: refused by the resource limits, exit code 1.
        self.assertEqual((rows["torus_small.step"]["status"], rows["torus_small.step"]["exit_code"]), ("usage", 1))
        self.assertEqual(rows["torus_small.step"]["settings"], {"level": "1", "max_faces": "10"})
        # Failed files are skipped unless --retry-failed.
        failed = sum(r["status"] != "ok" for r in s.files)
        s2 = batch.run([self.inputs], again, FAST, workers=2, cli=CLI, retry_failed=True)
        self.assertEqual(s2.converted, failed)

    def test_dask_missing(self):
        """Without Dask's distributed package the local pool works and --scheduler says how to
        install it."""
        saved = sys.modules.get("distributed")
        sys.modules["distributed"] = None  # import distributed raises ImportError
        try:
            with self.assertRaisesRegex(batch.BatchError, "apt-get install python3-distributed"):
                batch.run([os.path.join(CORPUS, "catmark_cube.obj")], os.path.join(self.tmp, "nodask"), FAST,
                          scheduler="tcp://127.0.0.1:1", cli=CLI)
            s = batch.run([os.path.join(CORPUS, "catmark_cube.obj")], os.path.join(self.tmp, "nodask"), FAST, cli=CLI)
            self.assertEqual(s.counts, {"ok": 1})
        finally:
            if saved is None:
                del sys.modules["distributed"]
            else:
                sys.modules["distributed"] = saved

    def test_unknown_setting_refused(self):
        with self.assertRaisesRegex(batch.BatchError, "unknown setting 'levle'"):
            batch.run([self.inputs], os.path.join(self.tmp, "x"), {"levle": 1}, cli=CLI)


FAKE_CONVERTER = """#!/bin/sh
# The real converter, except for inputs named hang* (sleeps) and crash* (dies of SIGSEGV).
case "$(basename "$2")" in
  hang*) echo $$ >> "{pids}"; exec sleep 1000 ;;
  crash*) kill -SEGV $$ ;;
esac
exec "{cli}" "$@"
"""


class Limits(unittest.TestCase):
    def test_hang_killed_crash_classified(self):
        tmp = tempfile.mkdtemp(prefix="s2n-batch-limits-")
        self.addCleanup(shutil.rmtree, tmp, True)
        inputs = os.path.join(tmp, "in")
        os.makedirs(inputs)
        for name in ("hang1.obj", "hang2.obj", "crash.obj", "cube.obj"):
            shutil.copy(os.path.join(CORPUS, "catmark_cube.obj"), os.path.join(inputs, name))
        pids = os.path.join(tmp, "pids")
        fake = os.path.join(tmp, "fake-subd2nurbs")
        with open(fake, "w", encoding="utf-8") as f:
            f.write(FAKE_CONVERTER.replace("{pids}", pids).replace("{cli}", CLI))
        os.chmod(fake, 0o755)
        s = batch.run([inputs], os.path.join(tmp, "out"), FAST, workers=2, cli=fake, timeout=2)
        rows = {r["output"]: r for r in s.files}
        self.assertEqual(rows["hang1.step"]["status"], "timeout")
        self.assertEqual(rows["hang2.step"]["status"], "timeout")
        self.assertEqual(rows["crash.step"]["status"], "crash")
        self.assertIn("SIGSEGV", rows["crash.step"]["message"])
        self.assertEqual(rows["cube.step"]["status"], "ok")
        with open(pids, encoding="utf-8") as f:
            hung = [int(line) for line in f]
        self.assertEqual(len(hung), 2)
        for pid in hung:  # killed, not left running
            with self.assertRaises(ProcessLookupError):
                os.kill(pid, 0)

    def test_memory_limit(self):
        """An address-space limit too small for the conversion (the car needs about 300 MB of
        address space at level 0) fails that file only, as out of memory (exit code 4); the
        converter's own estimate is set out of the way (max_memory 1G)."""
        tmp = tempfile.mkdtemp(prefix="s2n-batch-mem-")
        self.addCleanup(shutil.rmtree, tmp, True)
        s = batch.run([os.path.join(CORPUS, "catmark_car.obj"), os.path.join(CORPUS, "catmark_cube.obj")], tmp,
                      dict(FAST, max_memory="1G"), workers=1, cli=CLI, memory="120M")
        car, cube = s.files
        self.assertEqual((car["status"], car["exit_code"]), ("out-of-memory", 4), car)
        self.assertFalse(os.path.exists(os.path.join(tmp, "catmark_car.step")))
        self.assertEqual(cube["status"], "ok", cube)


# A few shapes of the corpus with different structure (quads, a torus, a pole, triangles, a
# crease), for the format tests.
FEW = ("catmark_cube", "catmark_torus", "catmark_pole8", "catmark_toroidal_tet", "catmark_edgecorner")


class Formats(unittest.TestCase):
    """IGES and BREP are deterministic too: with SOURCE_DATE_EPOCH the files of 1 and 2 workers
    (different orders and concurrency) and of a plain `subd2nurbs convert` are byte-identical;
    the IGES global section's dates are those of the epoch (1700000000 is 2023-11-14 22:13:20
    UTC) and it names no author."""

    def test_iges_and_brep_identical(self):
        tmp = tempfile.mkdtemp(prefix="s2n-batch-fmt-")
        self.addCleanup(shutil.rmtree, tmp, True)
        files = [os.path.join(CORPUS, n + ".obj") for n in FEW]
        for fmt in ("iges", "brep"):
            one = batch.run(files, os.path.join(tmp, fmt + "1"), FAST, workers=1, cli=CLI, output_format=fmt)
            two = batch.run(list(reversed(files)), os.path.join(tmp, fmt + "2"), FAST, workers=2, cli=CLI,
                            output_format=fmt)
            self.assertEqual(one.counts, {"ok": len(FEW)})
            self.assertEqual(two.counts, {"ok": len(FEW)})
            for stem in FEW:
                plain = os.path.join(tmp, "%s.%s" % (stem, fmt))
                time.sleep(1.1 if fmt == "iges" and stem == FEW[0] else 0)  # another second of the clock
                subprocess.run([CLI, "convert", os.path.join(CORPUS, stem + ".obj"), "-o", plain, "-q", "--level",
                                "0"], check=True, env=env())
                for run_dir in (fmt + "1", fmt + "2"):
                    self.assertTrue(same_bytes(plain, os.path.join(tmp, run_dir, "%s.%s" % (stem, fmt))),
                                    (stem, run_dir))
        with open(os.path.join(tmp, "iges1", "catmark_cube.iges"), encoding="ascii") as f:
            lines = f.read().splitlines()
        global_section = "".join(line[:72] for line in lines if line[72:73] == "G")
        self.assertEqual(global_section.count("15H20231114.221320"), 2, global_section)
        login = os.environ.get("USER") or os.environ.get("LOGNAME") or "root"
        self.assertNotIn("%dH%s," % (len(login), login), global_section)


class Threads(unittest.TestCase):
    def test_threads_per_file(self):
        """Each converter gets the cores shared by the files converted at once (cores // workers,
        at least 1; the report's timings_ms.threads says what it used), --threads overrides it,
        and changing it alone converts nothing again (the output does not depend on it)."""
        tmp = tempfile.mkdtemp(prefix="s2n-batch-threads-")
        self.addCleanup(shutil.rmtree, tmp, True)
        files = [os.path.join(CORPUS, n + ".obj") for n in FEW]
        cores = len(os.sched_getaffinity(0))

        def used(outdir, summary):
            self.assertEqual(summary.counts, {"ok": len(FEW)})
            out = set()
            for row in summary.files:
                with open(os.path.join(outdir, row["report"]), encoding="utf-8") as f:
                    out.add(json.load(f)["timings_ms"]["threads"])
            return out

        for workers in (1, 2):
            outdir = os.path.join(tmp, "w%d" % workers)
            s = batch.run(files, outdir, FAST, workers=workers, cli=CLI)
            self.assertEqual(used(outdir, s), {max(1, cores // workers)}, workers)
        given = os.path.join(tmp, "given")
        self.assertEqual(used(given, batch.run(files, given, dict(FAST, threads=1), workers=1, cli=CLI)), {1})
        again = batch.run(files, os.path.join(tmp, "w1"), dict(FAST, threads=1), workers=1, cli=CLI)
        self.assertEqual((again.converted, again.skipped), (0, len(FEW)))
        for stem in FEW:
            self.assertTrue(same_bytes(os.path.join(tmp, "w1", stem + ".step"), os.path.join(given, stem + ".step")),
                            stem)


# The slowest shapes (over 0.5 s each), left out of the runs that compare backends and resume
# (two thirds of the time).
HEAVY = ("catmark_pole360", "catmark_rook", "catmark_car", "catmark_bishop", "catmark_lefthanded",
         "catmark_smoothtris0", "catmark_smoothtris1", "catmark_pole64", "catmark_pawn", "catmark_helmet",
         "catmark_righthanded", "catmark_chaikin1", "catmark_val2_foldover", "catmark_xord_interior",
         "catmark_gregory_test7")


def light_tree(root):
    """The shared input tree without HEAVY (same relative paths)."""
    if not os.path.isdir(root):
        shutil.copytree(SHARED["inputs"], root, ignore=shutil.ignore_patterns(*[h + ".obj" for h in HEAVY]))
    return root


def check_like_reference(test, outdir, files):
    """The rows of a run over the light tree are the reference run's; its outputs are
    byte-identical to the reference's."""
    reference = {r["output"]: stable(r) for r in test.reference_json()["files"]}
    test.assertEqual(len(files), len(reference) - len(HEAVY))
    for row in files:
        test.assertEqual(stable(row), reference[row["output"]])
    for rel in outputs(outdir):
        test.assertTrue(filecmp.cmp(os.path.join(outdir, rel), os.path.join(test.reference, rel), shallow=False), rel)
    test.assertEqual(len(outputs(outdir)), sum(r["status"] == "ok" for r in files))


def dask_program(name):
    path = shutil.which(name) or os.path.join(os.path.dirname(sys.executable), name)
    if not os.path.exists(path):
        raise AssertionError("%s not found: install python3-distributed (scripts/bootstrap.sh)" % name)
    return path


class Dask(BatchTestCase):
    """A real cluster on 127.0.0.1: dask-scheduler and 2 dask-workers (no nanny, one thread
    each), on ports the scheduler picks (--port 0, the address read from its scheduler file)."""

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        cls.cluster = tempfile.mkdtemp(prefix="s2n-dask-")
        cls.scheduler_file = os.path.join(cls.cluster, "scheduler.json")
        cls.logs = []
        cls.procs = {}
        # Not the workers' own: the batch passes its SOURCE_DATE_EPOCH on with each task.
        worker_env = {k: v for k, v in os.environ.items() if k != "SOURCE_DATE_EPOCH"}
        worker_env.update(batch.dask_environment())  # as README advises (subd2nurbs-batch --dask-env)
        cls.procs["scheduler"] = cls.start(
            [dask_program("dask-scheduler"), "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
             "--scheduler-file", cls.scheduler_file], worker_env)
        wait_for(lambda: os.path.exists(cls.scheduler_file), "the scheduler file", 120)
        for name in ("w1", "w2"):  # each in a working folder of its own
            os.makedirs(os.path.join(cls.cluster, name))
            cls.procs[name] = cls.start(
                [dask_program("dask-worker"), "--scheduler-file", cls.scheduler_file, "--nthreads", "1",
                 "--no-nanny", "--no-dashboard", "--host", "127.0.0.1", "--name", name,
                 "--local-directory", os.path.join(cls.cluster, name)], worker_env, os.path.join(cls.cluster, name))
        import distributed
        with distributed.Client(scheduler_file=cls.scheduler_file, timeout="120s") as client:
            client.wait_for_workers(2, timeout=120)
            cls.address = client.scheduler.address

    @classmethod
    def start(cls, command, environment, cwd=None):
        log = open(os.path.join(cls.cluster, os.path.basename(command[0]) + "-%d.log" % len(cls.logs)), "w")
        cls.logs.append(log)
        return subprocess.Popen(command, env=environment, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True, cwd=cwd)

    @classmethod
    def tearDownClass(cls):
        for proc in reversed(list(cls.procs.values())):
            if proc.poll() is None:
                proc.terminate()
        for proc in cls.procs.values():
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        for log in cls.logs:
            log.close()
        shutil.rmtree(cls.cluster, ignore_errors=True)

    def test_1_same_as_local_pool(self):
        out = os.path.join(self.tmp, "dask")
        # The workers read and write the client's paths (this machine's files: a shared path).
        s = batch.run([light_tree(os.path.join(self.tmp, "light"))], out, FAST, scheduler=self.address, cli=CLI,
                      send_inputs="never")
        self.assertEqual(s.backend, "dask")
        self.assertEqual(s.converted, len(s.files))
        check_like_reference(self, out, s.files)

    def test_0_inputs_sent_as_bytes(self):
        """--send-inputs always: every input goes to the workers as bytes. The converter on the
        workers is given a private temporary copy (its log: a path in a subd2nurbs-batch-
        temporary folder, not the input tree, removed afterwards, run in the worker's own
        working folder); the outputs come back byte-identical to the local pool's, the summary
        rows are the same (messages naming the client's paths) and so are the reports (their
        "input" the client's path)."""
        work = tempfile.mkdtemp(prefix="s2n-sent-")
        self.addCleanup(shutil.rmtree, work, True)
        fake, log = logging_converter(work)
        light = light_tree(os.path.join(self.tmp, "light"))
        out = os.path.join(self.tmp, "dask-sent")
        s = batch.run([light], out, FAST, scheduler=self.address, cli=fake, send_inputs="always")
        self.assertEqual(s.converted, len(s.files))
        check_like_reference(self, out, s.files)
        reports = 0
        for row in s.files:
            if row["status"] != "ok":
                continue
            mine = report_without_times(os.path.join(out, row["report"]))
            self.assertEqual(mine.pop("input"), os.path.abspath(row["input"]))
            theirs = report_without_times(os.path.join(self.reference, row["report"]))
            theirs.pop("input")
            # Warnings name the input: each run's own input tree.
            self.assertEqual(json.dumps(mine, sort_keys=True).replace(light, "ROOT"),
                             json.dumps(theirs, sort_keys=True).replace(self.inputs, "ROOT"), row["output"])
            reports += 1
        self.assertGreater(reports, 50)
        with open(log, encoding="utf-8") as f:
            given = [line.rstrip("\n").split("\t") for line in f]
        self.assertEqual(len(given), len(s.files))
        workers = {os.path.join(self.cluster, "w1"), os.path.join(self.cluster, "w2")}
        for path, cwd in given:
            self.assertIn("subd2nurbs-batch-", path)
            self.assertFalse(os.path.realpath(path).startswith(os.path.realpath(light)), path)
            self.assertFalse(os.path.exists(path), path)  # the temporary copy is removed
            self.assertIn(cwd, workers)
        self.assertEqual(sorted(os.path.basename(p) for p, _ in given),
                         sorted(os.path.basename(r["input"]) for r in s.files))

    def test_0_sent_gltf_buffers_and_iges(self):
        """A .gltf whose external buffer lies in a folder beside its own ("../buffers/...") is
        sent with its buffer; IGES files converted by the cluster from sent inputs are
        byte-identical to a plain convert's."""
        tmp = tempfile.mkdtemp(prefix="s2n-sent-gltf-")
        self.addCleanup(shutil.rmtree, tmp, True)
        gltf = os.path.join(tmp, "in", "models", "cube.gltf")
        write_cube_gltf(gltf, "../buffers/cube.bin")
        files = [gltf] + [os.path.join(CORPUS, n + ".obj") for n in FEW]
        for fmt in ("step", "iges"):
            out = os.path.join(tmp, "out-" + fmt)
            s = batch.run(files, out, FAST, scheduler=self.address, cli=CLI, send_inputs="always",
                          output_format=fmt)
            self.assertEqual(s.counts, {"ok": len(files)}, s.files)
            for path in files:
                stem = os.path.splitext(os.path.basename(path))[0]
                plain = os.path.join(tmp, "plain-%s.%s" % (stem, fmt))
                subprocess.run([CLI, "convert", path, "-o", plain, "-q", "--level", "0"], check=True, env=env())
                self.assertTrue(same_bytes(plain, os.path.join(out, "%s.%s" % (stem, fmt))), (stem, fmt))

    def test_2_interrupt_and_resume(self):
        """SIGINT to a batch on the cluster (inputs sent as bytes): it ends with exit code 130
        and its summary; the same command again converts exactly the files left and ends with
        the local pool's outputs and rows."""
        out = os.path.join(self.tmp, "dask-interrupted")
        args = batch_command(light_tree(os.path.join(self.tmp, "light")), "-o", out, "--scheduler", self.address,
                             "--send-inputs", "always", "--level", "0")
        left = interrupt_after(self, args, out, 10, timeout=300)
        second = subprocess.run(args, env=env(), stderr=subprocess.DEVNULL, timeout=600)
        self.assertEqual(second.returncode, 2)  # some inputs fail, as in the reference
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            final = json.load(f)
        self.assertEqual(final["run"]["converted"], len(left))
        check_like_reference(self, out, final["files"])

    def test_3_lost_worker(self):
        """SIGKILL to one worker mid-run: its task runs again on the other; every file done."""
        out = os.path.join(self.tmp, "dask-lost")
        args = batch_command(light_tree(os.path.join(self.tmp, "light")), "-o", out, "--scheduler", self.address,
                             "--level", "0")
        run = subprocess.Popen(args, env=env(), stderr=subprocess.DEVNULL)
        wait_for(lambda: journal_lines(out) >= 10 or run.poll() is not None, "10 files converted")
        self.assertIsNone(run.poll(), "the batch ended before the worker was killed")
        self.procs["w1"].kill()
        self.procs["w1"].wait()
        self.assertEqual(run.wait(timeout=600), 2)  # some inputs fail, as in the reference
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            data = json.load(f)
        self.assertEqual(data["run"]["converted"], len(data["files"]))
        check_like_reference(self, out, data["files"])


class Interrupt(BatchTestCase):
    def test_sigint_then_resume(self):
        out = os.path.join(self.tmp, "interrupted")
        light = light_tree(os.path.join(self.tmp, "light"))
        args = batch_command(light, "-o", out, "--workers", "2", "--level", "0")
        left = interrupt_after(self, args, out, 20, timeout=120)
        # No temporary file of a killed converter is left behind.
        leftovers = [n for _, _, files in os.walk(out) for n in files if n.endswith(".tmp")]
        self.assertEqual(leftovers, [])
        second = subprocess.run(args, env=env(), stderr=subprocess.DEVNULL)
        self.assertEqual(second.returncode, 2)  # some inputs fail, as in the reference
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            final = json.load(f)
        self.assertEqual(final["run"]["converted"], len(left))
        self.assertEqual(final["run"]["skipped"], len(final["files"]) - len(left))
        check_like_reference(self, out, final["files"])


if __name__ == "__main__":
    unittest.main()
