"""Batch conversion of a library of cages and meshes: ``subd2nurbs-batch`` /
``python3 -m subd2nurbs.batch`` / :func:`run`.

Every file is converted by the ``subd2nurbs convert`` command line in a process of its own, with
a wall-time limit (``--timeout``) and an address-space limit (RLIMIT_AS, plus the converter's own
``--max-memory`` estimate), so a crash, a hang or running out of memory costs that file only::

    subd2nurbs-batch models/ -o out/                      # local pool, one worker per core
    subd2nurbs-batch models/ -o out/ --workers 4 --timeout 600 --tolerance 1e-3
    subd2nurbs-batch --manifest list.csv -o out/          # input, output, per-file settings
    subd2nurbs-batch models/ -o out/ --scheduler tcp://head:8786   # a Dask cluster
    subd2nurbs-batch models/ -o out/ --dask-local 2       # a Dask cluster on this machine

The output tree mirrors the input tree: ``out/a/b/part.step`` and its report
``out/a/b/part.report.json`` for ``models/a/b/part.obj``. ``out/summary.json`` and
``out/summary.csv`` hold a row per input (docs/formats.md, "Batch summary"). A re-run with the same
output folder skips the files whose input and settings are unchanged and whose output exists
(failed files too, unless ``--retry-failed``).

The Python API::

    from subd2nurbs import batch
    summary = batch.run(["models/"], "out/", {"tolerance": 1e-3}, workers=2)
    summary.counts          # {"ok": 85, "invalid-input": 2}
    summary.files[0]        # the summary row of the first input (a dict)

Dask (Debian ``python3-distributed``) is optional: without it the local pool works. On a
scheduler's cluster the inputs up to ``--send-limit`` (8M) are sent to the workers as bytes and
their outputs and reports come back (``--send-inputs always|never`` to choose); the larger ones
are read and written by the workers on the client's paths (a shared folder). The client's
``SOURCE_DATE_EPOCH`` goes with every task: STEP and IGES files are then byte-identical whatever
the order, the worker count or the backend.
"""

import argparse
import csv
import ctypes
import ctypes.util
import hashlib
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

#: The extensions of the files a folder contributes (the readers of ``subd2nurbs convert``).
EXTENSIONS = (".obj", ".glb", ".gltf", ".stl", ".ply", ".off")

#: Output formats (the extension of the converted file).
FORMATS = ("step", "iges", "brep", "json")

#: The failure class of each exit code of ``subd2nurbs convert`` (converter/pipeline/errors.cpp).
EXIT_CLASSES = {1: "usage", 2: "invalid-input", 3: "write-failure", 4: "internal-error"}

#: Failure classes the batch itself assigns.
TIMEOUT = "timeout"            # killed at the wall-time limit
CRASH = "crash"                # ended by a signal (segmentation fault, abort, the OOM killer)
OUT_OF_MEMORY = "out-of-memory"  # the converter ran out of memory under the address-space limit
NO_OUTPUT = "no-output"        # exit code 0 but no output or report
INTERRUPTED = "interrupted"    # the batch was interrupted before the file was finished
START_FAILURE = "start-failure"  # the converter could not be started

#: The columns of summary.csv, in order.
CSV_COLUMNS = ("input", "output", "status", "exit_code", "message", "faces", "poles", "deviation",
               "deviation_relative", "g1_angle_deg", "time_s", "cpu_s", "peak_memory_mb", "input_hash",
               "settings_hash")

SUMMARY_FORMAT = "subd2nurbs-batch-summary"
#: On a Dask scheduler's cluster, inputs up to this size are sent as bytes (send_inputs "auto").
SEND_LIMIT = 8 << 20
SEND_MODES = ("auto", "always", "never")
JOURNAL = ".subd2nurbs-batch.journal"
KILL_GRACE_S = 3.0
MESSAGE_LIMIT = 500

#: Settings of ``convert`` that a batch does not pass (it writes no preview; samples is check's).
_NOT_BATCH_SETTINGS = ("samples", "preview", "preview_samples", "brep")


class BatchError(Exception):
    """A batch that cannot start: no inputs, a bad manifest, an unknown setting, no converter."""


# --- settings --------------------------------------------------------------------------------

def settings_rows():
    """The rows of the converter's settings table a batch passes on: {name: row} (name, type,
    cli flag, help)."""
    from . import _subd2nurbs
    return {row["name"]: row for row in _subd2nurbs.settings_table()
            if row["cli"] and row["name"] not in _NOT_BATCH_SETTINGS}


def _truthy(value):
    if isinstance(value, str):
        word = value.strip().lower()
        if word in ("1", "true", "yes", "on"):
            return True
        if word in ("", "0", "false", "no", "off"):
            return False
        raise BatchError("a flag setting takes true/false, not %r" % value)
    return bool(value)


def normalized_settings(settings, rows=None):
    """`settings` ({name: value}, names as in docs/settings.md) with None / empty values dropped,
    values as the command line spells them (text; flags True), sorted by name. Unknown names are
    refused."""
    rows = settings_rows() if rows is None else rows
    out = {}
    for name, value in (settings or {}).items():
        if name not in rows:
            raise BatchError("unknown setting %r (the settings of convert: %s)" % (name, ", ".join(sorted(rows))))
        if value is None or (isinstance(value, str) and value.strip() == ""):
            continue
        if rows[name]["type"] == "flag":
            if _truthy(value):
                out[name] = True
            continue
        if isinstance(value, bool):
            value = "on" if value else "off"
        out[name] = value if isinstance(value, str) else repr(value) if isinstance(value, float) else str(value)
    return dict(sorted(out.items()))


def settings_args(settings, rows=None):
    """The command-line arguments of normalized settings."""
    rows = settings_rows() if rows is None else rows
    args = []
    for name, value in settings.items():
        flag = rows[name]["cli"]
        args += [flag] if value is True else [flag, value]
    return args


#: Settings that do not change the output (a conversion on one thread is the same to the bit as
#: on all of them): not part of the settings hash, so changing them does not convert again.
_OUTPUT_NEUTRAL_SETTINGS = ("threads",)


def settings_hash(settings, fmt):
    kept = {k: v for k, v in settings.items() if k not in _OUTPUT_NEUTRAL_SETTINGS}
    text = json.dumps({"format": fmt, "settings": kept}, sort_keys=True)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()[:16]


def file_hash(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return "sha256:" + h.hexdigest()


def memory_bytes(text):
    """'512M', '2G', '1048576' -> bytes (K/M/G/T are powers of 1024)."""
    if isinstance(text, (int, float)):
        return int(text)
    t = text.strip().upper().rstrip("B").rstrip("I")
    scale = {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}.get(t[-1:], 1)
    try:
        return int(float(t[:-1] if scale > 1 else t) * scale)
    except ValueError:
        raise BatchError("bad memory size %r (bytes, or with K/M/G/T)" % text) from None


# --- the jobs --------------------------------------------------------------------------------

class Job:
    """One input: where it is, where its output and report go (relative to the output folder)
    and its own settings."""

    def __init__(self, input_path, rel, settings):
        self.input = input_path
        self.rel = rel              # the input's path relative to its root: the tree mirrored
        self.output = None          # relative to the output folder
        self.report = None
        self.settings = settings


def _walk(root):
    found = []
    for folder, dirs, files in os.walk(root):
        dirs.sort()
        for name in sorted(files):
            if os.path.splitext(name)[1].lower() in EXTENSIONS:
                found.append(os.path.join(folder, name))
    return found


def _jobs_from_paths(paths, settings):
    jobs = []
    folders = [p for p in paths if os.path.isdir(p)]
    for p in paths:
        if os.path.isdir(p):
            prefix = "" if len(folders) == 1 else os.path.basename(os.path.normpath(p))
            for f in _walk(p):
                jobs.append(Job(f, os.path.join(prefix, os.path.relpath(f, p)), dict(settings)))
        elif os.path.isfile(p):
            jobs.append(Job(p, os.path.basename(p), dict(settings)))
        else:
            raise BatchError("%s: no such file or folder" % p)
    return jobs


def _manifest_rows(path):
    with open(path, newline="", encoding="utf-8") as f:
        text = f.read()
    if path.lower().endswith(".json"):
        data = json.loads(text)
        rows = data.get("files") if isinstance(data, dict) else data
        if not isinstance(rows, list):
            raise BatchError("%s: a JSON manifest is a list of {input, output, settings} objects "
                             "(or an object with such a 'files' list)" % path)
        out = []
        for i, row in enumerate(rows):
            if isinstance(row, str):
                row = {"input": row}
            if not isinstance(row, dict) or not isinstance(row.get("input"), str):
                raise BatchError("%s: entry %d has no 'input'" % (path, i))
            extra = {k: v for k, v in row.items() if k not in ("input", "output", "settings")}
            settings = dict(row.get("settings") or {}, **extra)
            out.append((i + 1, row["input"], row.get("output"), settings))
        return out
    reader = csv.DictReader(io.StringIO(text))
    if not reader.fieldnames or "input" not in reader.fieldnames:
        raise BatchError("%s: a CSV manifest needs a header line with an 'input' column" % path)
    out = []
    for row in reader:
        settings = {k: v for k, v in row.items() if k not in ("input", "output") and k is not None}
        out.append((reader.line_num, row["input"], row.get("output") or None, settings))
    return out


def _jobs_from_manifest(path, settings, rows):
    base = os.path.dirname(os.path.abspath(path))
    jobs = []
    for line, input_path, output, own in _manifest_rows(path):
        full = input_path if os.path.isabs(input_path) else os.path.join(base, input_path)
        rel = os.path.relpath(full, base)
        if rel.startswith(".."):
            rel = os.path.basename(full)
        try:
            merged = dict(settings, **normalized_settings(own, rows))
        except BatchError as e:
            raise BatchError("%s:%d: %s" % (path, line, e)) from None
        job = Job(full, rel, merged)
        job.output = output
        jobs.append(job)
    return jobs


def _place_outputs(jobs, fmt):
    """Output and report names mirroring the input tree; inputs that would share an output
    (part.obj and part.ply) keep their extension in it (part.obj.step)."""
    stems = {}
    for job in jobs:
        stem = os.path.splitext(job.rel)[0]
        stems[stem] = stems.get(stem, 0) + 1
    for job in jobs:
        stem = os.path.splitext(job.rel)[0]
        if stems[stem] > 1:
            stem = job.rel
        if job.output is None:
            job.output = stem + "." + fmt
        else:
            stem = os.path.splitext(job.output)[0]
        job.report = stem + ".report.json"
    seen = {}
    for job in jobs:
        if job.output in seen:
            raise BatchError("%s and %s would both be written to %s" % (seen[job.output], job.input, job.output))
        seen[job.output] = job.input


def collect_jobs(inputs, settings, fmt="step", manifest=None, rows=None):
    """The jobs of folders / files `inputs` and of a manifest, each with its output names."""
    rows = settings_rows() if rows is None else rows
    base = normalized_settings(settings, rows)
    jobs = _jobs_from_paths(list(inputs or []), base)
    if manifest:
        jobs += _jobs_from_manifest(manifest, base, rows)
    if not jobs:
        raise BatchError("no input files (folders are searched for %s)" % ", ".join(EXTENSIONS))
    _place_outputs(jobs, fmt)
    return jobs


# --- one file, in a process of its own (runs on the pool's threads or on Dask workers) ------

_PR_SET_PDEATHSIG = 1
_libc = None


def _load_libc():
    global _libc
    if _libc is None:
        try:
            _libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        except OSError:
            _libc = False
    return _libc


def _limits(memory):
    libc = _load_libc()  # loaded before the fork: the child only calls into it

    def apply():
        if libc:
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)  # ends (its temporaries removed) with its starter
        if memory:
            import resource
            resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    return apply


_running = set()          # the converters running in this process (for interrupting them)
_running_lock = threading.Lock()
_stopping = threading.Event()  # set when the batch is interrupted: start no more converters


def _kill_group(proc, first=signal.SIGTERM):
    """SIGTERM to the converter's process group (it removes its temporary files), SIGKILL after
    a grace period."""
    for sig in (first, signal.SIGKILL):
        try:
            os.killpg(proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            return
        if sig == signal.SIGKILL:
            return
        deadline = time.monotonic() + KILL_GRACE_S
        while time.monotonic() < deadline:
            try:
                os.killpg(proc.pid, 0)
            except ProcessLookupError:
                return
            time.sleep(0.05)


def terminate_running():
    """Stops every converter this process is running (the batch was interrupted)."""
    with _running_lock:
        _stopping.set()
        procs = list(_running)
    for proc in procs:
        proc.subd2nurbs_interrupted = True
        threading.Thread(target=_kill_group, args=(proc,), daemon=True).start()


def stop_run(run_id):
    """Stops the converters of the batch `run_id` that this process (a Dask worker) is running,
    and no other's: the interrupted client's cancelled tasks do not keep the workers busy.
    Returns how many."""
    with _running_lock:
        procs = [p for p in _running if getattr(p, "subd2nurbs_run", None) == run_id]
    for proc in procs:
        proc.subd2nurbs_interrupted = True
        threading.Thread(target=_kill_group, args=(proc,), daemon=True).start()
    return len(procs)


def _message(stderr_text):
    lines = [l.strip() for l in stderr_text.splitlines() if l.strip()]
    errors = [l for l in lines if "error" in l.lower() or "out of memory" in l.lower()]
    text = " | ".join(errors or lines[-3:])
    return text if len(text) <= MESSAGE_LIMIT else text[:MESSAGE_LIMIT - 3] + "..."


def _measures(report):
    """The summary's columns taken from a convert report."""
    faces = report.get("faces") or {}
    deviation = report.get("deviation") or {}
    continuity = report.get("continuity") or {}
    return {"faces": faces.get("total"), "poles": faces.get("poles"), "deviation": deviation.get("max"),
            "deviation_relative": deviation.get("relative"),
            "g1_angle_deg": continuity.get("max_normal_angle_deg")}


def _json_quoted(text):
    """`text` as the converter's JSON writer quotes it (io/json_writer.cpp), as bytes."""
    out = bytearray(b'"')
    for c in os.fsencode(text):
        if c == 0x22:
            out += b'\\"'
        elif c == 0x5C:
            out += b'\\\\'
        elif c == 0x0A:
            out += b'\\n'
        elif c == 0x0D:
            out += b'\\r'
        elif c == 0x09:
            out += b'\\t'
        elif c < 0x20:
            out += b'\\u%04x' % c
        else:
            out.append(c)
    return bytes(out + b'"')


def convert_one(task, payload=None):
    """Converts one file with the command line in a process of its own and returns its summary
    row. `task`: cli, input, output and report (absolute paths), args (the settings' arguments),
    timeout (s, 0: none), memory (bytes of address space, 0: none), env (variables for the
    converter: the client's SOURCE_DATE_EPOCH). Pure and idempotent (the
    outputs are written atomically), so a backend may run it again elsewhere.

    With `payload` (the bytes of :func:`pack_input`: the input and the files it refers to, for
    a worker that cannot see the client's path) the input is written to a private temporary
    folder under its own name, converted there, and the row carries the output's and the
    report's bytes (row["files"], {"output": bytes, "report": bytes}) for the client to write;
    the paths in the messages and the report are the client's."""
    if payload is not None:
        return _convert_sent(task, payload)
    if not os.path.isfile(task["input"]):
        row = _empty_row()
        row.update(status=START_FAILURE, message="%s: the worker cannot read this file (not on a path it shares "
                                                 "with the client?); files up to the send limit are sent as bytes"
                                                 % task["input"])
        return row
    for path in (task["output"], task["report"]):
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    return _run_converter(task, task["input"], task["output"], task["report"])


def pack_input(path):
    """The bytes a worker needs to convert `path` without seeing it: the file and, for a .gltf,
    the external buffers it names (relative "uri"s; images are not read by the converter), as
    {"name": the file's name, "depth": how many folders up the buffers reach, "files": [(path
    relative to the input's folder, bytes)]}, pickled."""
    import pickle
    folder, name = os.path.split(os.path.abspath(path))
    with open(path, "rb") as f:
        files = [(name, f.read())]
    depth = 0
    if name.lower().endswith(".gltf"):
        from urllib.parse import unquote
        try:
            buffers = json.loads(files[0][1].decode("utf-8")).get("buffers") or []
        except (ValueError, UnicodeDecodeError, AttributeError):
            buffers = []  # the converter says what is wrong with it
        seen = set()
        for buffer in buffers:
            uri = buffer.get("uri") if isinstance(buffer, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:") or "://" in uri or os.path.isabs(unquote(uri)):
                continue
            rel = os.path.normpath(unquote(uri))
            source = os.path.join(folder, rel)
            if rel in seen or not os.path.isfile(source):
                continue  # a missing buffer: the converter reports it
            seen.add(rel)
            with open(source, "rb") as f:
                files.append((rel, f.read()))
            ups = 0
            for part in rel.split(os.sep):
                if part != "..":
                    break
                ups += 1
            depth = max(depth, ups)
    return pickle.dumps({"name": name, "depth": depth, "files": files}, protocol=4)


def _convert_sent(task, payload):
    import pickle
    data = pickle.loads(payload)
    tmp = tempfile.mkdtemp(prefix="subd2nurbs-batch-")
    try:
        folder = os.path.join(tmp, "in", *(["d"] * data["depth"]))
        os.makedirs(folder)
        local_input = os.path.join(folder, data["name"])
        for rel, blob in data["files"]:
            path = os.path.normpath(os.path.join(folder, rel))
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "wb") as f:
                f.write(blob)
        os.makedirs(os.path.join(tmp, "out"))
        local_output = os.path.join(tmp, "out", os.path.basename(task["output"]))
        local_report = os.path.join(tmp, "out", "report", os.path.basename(task["report"]))
        os.makedirs(os.path.dirname(local_report))
        renames = [(local_input, task["input"]), (local_output, task["output"]), (local_report, task["report"])]
        row = _run_converter(task, local_input, local_output, local_report, renames)
        files = {}
        if os.path.exists(local_output):
            with open(local_output, "rb") as f:
                files["output"] = f.read()
        if os.path.exists(local_report):
            with open(local_report, "rb") as f:
                report = f.read()
            for here, there in renames:  # "input", "output", warnings: the client's paths
                report = report.replace(_json_quoted(here)[1:-1], _json_quoted(there)[1:-1])
            files["report"] = report
        row["files"] = files
        return row
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _empty_row():
    return {"status": None, "exit_code": None, "message": "", "faces": None, "poles": None, "deviation": None,
            "deviation_relative": None, "g1_angle_deg": None, "time_s": None, "cpu_s": None, "peak_memory_mb": None}


def _run_converter(task, input_path, output, report_path, renames=()):
    """Runs the converter on `input_path` into `output` and `report_path` and classifies the
    outcome. `renames`: (path here, path to show) pairs for the messages."""
    command = [task["cli"], "convert", input_path, "-o", output, "--report", report_path, "-q"]
    command += task["args"]
    row = _empty_row()
    if _stopping.is_set():
        row.update(status=INTERRUPTED, message="the batch was interrupted")
        return row
    err = tempfile.TemporaryFile()
    start = time.monotonic()
    try:
        proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err,
                                preexec_fn=_limits(task.get("memory") or 0), start_new_session=True,
                                env=dict(os.environ, **task["env"]) if task.get("env") else None)
    except OSError as e:
        err.close()
        row.update(status=START_FAILURE, message="cannot start %s: %s" % (task["cli"], e.strerror or e))
        return row
    proc.subd2nurbs_interrupted = False
    proc.subd2nurbs_run = task.get("run")
    with _running_lock:
        _running.add(proc)
    waited = []
    waiter = threading.Thread(target=lambda: waited.append(os.wait4(proc.pid, 0)), daemon=True)
    waiter.start()
    timeout = task.get("timeout") or None
    waiter.join(timeout)
    timed_out = waiter.is_alive()
    if timed_out:
        _kill_group(proc)
        waiter.join()
    elapsed = time.monotonic() - start
    with _running_lock:
        _running.discard(proc)
    _, status, usage = waited[0]
    proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    err.seek(0)
    stderr_text = err.read(1 << 20).decode("utf-8", "replace")
    err.close()
    for here, there in renames:
        stderr_text = stderr_text.replace(here, there)
    row["time_s"] = round(elapsed, 3)
    row["cpu_s"] = round(usage.ru_utime + usage.ru_stime, 3)  # the converter's threads, user + system
    row["peak_memory_mb"] = round(usage.ru_maxrss / 1024.0, 1)  # KiB on Linux
    code = proc.returncode
    if proc.subd2nurbs_interrupted:
        row.update(status=INTERRUPTED, message="the batch was interrupted")
    elif timed_out:
        row.update(status=TIMEOUT, message="killed after the time limit of %g s" % timeout)
    elif code < 0:
        name = signal.Signals(-code).name if -code in signal.valid_signals() else str(-code)
        row.update(status=CRASH, exit_code=code,
                   message=("killed by %s" % name) + (": " + _message(stderr_text) if stderr_text.strip() else ""))
    elif code != 0:
        message = _message(stderr_text)
        status = EXIT_CLASSES.get(code, "exit-%d" % code)
        if code == 4 and ("out of memory" in stderr_text or "malloc failed" in stderr_text):
            status = OUT_OF_MEMORY
        elif code in (126, 127):  # the shell's or the loader's: not found, not executable, no libraries
            status = START_FAILURE
        row.update(status=status, exit_code=code, message=message)
    else:
        try:
            with open(report_path, encoding="utf-8") as f:
                report = json.load(f)
        except (OSError, ValueError) as e:
            report = None
            row.update(status=NO_OUTPUT, exit_code=0, message="no readable report: %s" % e)
        if report is not None:
            if not os.path.exists(output):
                row.update(status=NO_OUTPUT, exit_code=0, message="exit code 0 but no output file")
            else:
                warnings = "; ".join(report.get("warnings") or [])
                for here, there in renames:
                    warnings = warnings.replace(here, there)
                row.update(status="ok", exit_code=0, message=warnings[:MESSAGE_LIMIT])
                row.update(_measures(report))
    return row


# --- the summary -----------------------------------------------------------------------------

class Summary:
    """The outcome of a batch: ``files`` (one row per input, in input order), ``counts``
    ({status: number}), ``converted`` / ``skipped`` (this run), ``interrupted``."""

    def __init__(self, files, settings, fmt, converted, skipped, interrupted, backend):
        self.files = files
        self.settings = settings
        self.format = fmt
        self.converted = converted
        self.skipped = skipped
        self.interrupted = interrupted
        self.backend = backend
        self.counts = {}
        for row in files:
            self.counts[row["status"]] = self.counts.get(row["status"], 0) + 1

    @property
    def ok(self):
        return self.counts.get("ok", 0)

    @property
    def failed(self):
        return len(self.files) - self.ok

    def to_json(self):
        return {"format": SUMMARY_FORMAT, "version": 1, "output_format": self.format, "settings": self.settings,
                "counts": dict(sorted(self.counts.items())),
                "run": {"converted": self.converted, "skipped": self.skipped, "interrupted": self.interrupted,
                        "backend": self.backend},
                "files": self.files}

    def write(self, outdir):
        _write_atomic(os.path.join(outdir, "summary.json"),
                      json.dumps(self.to_json(), indent=2, sort_keys=False) + "\n")
        text = io.StringIO()
        w = csv.writer(text, lineterminator="\n")
        w.writerow(CSV_COLUMNS)
        for row in self.files:
            w.writerow(["" if row.get(c) is None else row.get(c) for c in CSV_COLUMNS])
        _write_atomic(os.path.join(outdir, "summary.csv"), text.getvalue())


def _write_atomic(path, data):
    """Writes text or bytes to `path` through a temporary file renamed over it."""
    tmp = "%s.%d.tmp" % (path, os.getpid())
    try:
        with open(tmp, "wb") as f:
            f.write(data.encode("utf-8") if isinstance(data, str) else data)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise


def _previous_rows(outdir):
    """The rows of the last run in `outdir`: its summary.json, then its journal (the rows of an
    interrupted run, one JSON line each), keyed by output."""
    rows = {}
    try:
        with open(os.path.join(outdir, "summary.json"), encoding="utf-8") as f:
            data = json.load(f)
        if data.get("format") == SUMMARY_FORMAT:
            rows = {r["output"]: r for r in data.get("files", []) if isinstance(r, dict) and "output" in r}
    except (OSError, ValueError):
        pass
    try:
        with open(os.path.join(outdir, JOURNAL), encoding="utf-8") as f:
            for line in f:
                try:
                    r = json.loads(line)
                except ValueError:
                    continue  # a line cut short by a crash
                rows[r["output"]] = r
    except OSError:
        pass
    return rows


def _resumable(prev, row, outdir, retry_failed):
    if not prev or prev.get("input_hash") != row["input_hash"] or prev.get("settings_hash") != row["settings_hash"]:
        return False
    status = prev.get("status")
    if status == "ok":
        return all(os.path.exists(os.path.join(outdir, prev[k])) for k in ("output", "report"))
    if status in (INTERRUPTED, START_FAILURE, None):
        return False
    return not retry_failed


# --- progress --------------------------------------------------------------------------------

class Progress:
    """A bar on a terminal (done / failed / ETA), else a line per file."""

    def __init__(self, total, stream=None, quiet=False):
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.total = total
        self.quiet = quiet
        self.done = 0
        self.failed = 0
        self.start = time.monotonic()
        self.to_do = total

    def skipped(self, n):
        self.done += n
        self.to_do = self.total - self.done
        if n and not self.quiet:
            self._print("subd2nurbs-batch: %d of %d files unchanged since the last run, skipped" % (n, self.total))

    def _print(self, line):
        if self.tty:
            self.stream.write("\r\033[K")
        self.stream.write(line + "\n")
        self.stream.flush()

    def file(self, input_path, row):
        self.done += 1
        ok = row["status"] == "ok"
        self.failed += not ok
        if self.quiet:
            return
        if self.tty:
            if not ok:
                self._print("subd2nurbs-batch: %s: %s: %s" % (input_path, row["status"], row["message"]))
            converted = self.done - (self.total - self.to_do)
            elapsed = time.monotonic() - self.start
            left = self.total - self.done
            eta = elapsed / converted * left if converted else 0
            width = 30
            filled = int(width * self.done / max(1, self.total))
            self.stream.write("\r\033[K[%s%s] %d/%d done, %d failed, ETA %d:%02d" % (
                "#" * filled, "." * (width - filled), self.done, self.total, self.failed, eta // 60, eta % 60))
            self.stream.flush()
        else:
            self.stream.write("subd2nurbs-batch: [%d/%d] %s %s%s\n" % (
                self.done, self.total, row["status"], input_path,
                "" if ok else ": " + row["message"]))
            self.stream.flush()

    def finish(self):
        if self.tty and not self.quiet:
            self.stream.write("\n")
            self.stream.flush()


# --- the backends ----------------------------------------------------------------------------

class LocalPool:
    """Threads of this process, each running one converter process at a time."""

    name = "local"

    def __init__(self, workers):
        from concurrent.futures import ThreadPoolExecutor
        self.workers = workers
        self.executor = ThreadPoolExecutor(max_workers=workers)

    def run(self, tasks):
        from concurrent.futures import as_completed
        futures = {self.executor.submit(convert_one, task): key for key, task in tasks}
        for future in as_completed(futures):
            yield futures[future], future.result()

    def interrupt(self, run_id=None):
        self.executor.shutdown(wait=False, cancel_futures=True)
        terminate_running()

    def close(self):
        self.executor.shutdown(wait=True)


def _import_distributed():
    try:
        import distributed
        return distributed
    except ImportError:
        raise BatchError("--scheduler and --dask-local need Dask's distributed package: "
                         "apt-get install python3-distributed (or pip install distributed)") from None


#: Dask settings for the processes of a batch cluster: no statistical profiler (it samples the
#: running task's stack 100 times a second) and the event loop's, memory and system monitors at
#: 1-2 s instead of 20-500 ms. An idle scheduler with 2 workers then takes about 0.014 instead of
#: 0.1 of a core (docs/benchmarks.md section 11), which the conversions get instead. As
#: environment variables (for dask-scheduler / dask-worker): :func:`dask_environment`.
DASK_CONFIG = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
               "distributed.worker.memory.monitor-interval": "1s",
               "distributed.admin.system-monitor.interval": "2s"}


def dask_environment():
    """DASK_CONFIG as the environment variables Dask's programs read."""
    return {"DASK_" + key.upper().replace(".", "__").replace("-", "_"): str(value)
            for key, value in DASK_CONFIG.items()}


class DaskBackend:
    """The same tasks on a Dask cluster: a scheduler's address, or a local cluster of `local`
    worker processes with one thread each. A task's input is read by the worker from the
    client's path (a shared path) or, when the task says "send", sent as bytes with the task
    (pack_input; held by the scheduler, so a lost worker's task can run again elsewhere) and its
    output and report come back as bytes.
    Tasks are handed to the scheduler in their order (largest first) a few at a time, so that
    only those in flight are held in memory. A lost worker's tasks are run again by Dask on
    another."""

    name = "dask"

    def __init__(self, scheduler=None, local=0):
        distributed = _import_distributed()
        self.cluster = None
        if scheduler:
            try:
                self.client = distributed.Client(scheduler, timeout="60s")
            except (OSError, TimeoutError) as e:
                raise BatchError("cannot reach the Dask scheduler at %s: %s" % (scheduler, e)) from None
        else:
            import dask
            with dask.config.set(DASK_CONFIG):  # passed on to the workers by their nannies
                self.cluster = distributed.LocalCluster(n_workers=local, threads_per_worker=1, processes=True,
                                                        dashboard_address=None)
            self.client = distributed.Client(self.cluster)
        self.futures = {}

    def _submit(self, task):
        task = dict(task)
        payload = None
        if task.pop("send", False):
            payload = pack_input(task["input"])
        # A key of the task's content, this run's id included: a task of an interrupted run that
        # is still ending on a worker is not taken for this run's.
        digest = hashlib.sha256(json.dumps(task, sort_keys=True).encode()).hexdigest()[:24]
        return self.client.submit(convert_one, task, payload, key="subd2nurbs-convert-" + digest, pure=False,
                                  retries=1)

    def run(self, tasks):
        import warnings
        from distributed import as_completed
        # Inputs sent as bytes are task arguments on purpose (see the class): not Dask's advice
        # to scatter them, which would lose them with the worker holding them.
        warnings.filterwarnings("ignore", message="Large object of size")
        pending = list(reversed(tasks))  # popped from the end: in the tasks' order
        try:
            threads = sum(self.client.nthreads().values())
        except Exception:
            threads = 0
        window = max(8, 3 * threads)  # enough queued that no worker waits for the next submit
        done = as_completed()
        while pending or self.futures:
            while pending and len(self.futures) < window:
                key, task = pending.pop()
                try:
                    future = self._submit(task)
                except OSError as e:  # the input vanished or became unreadable since the start
                    row = _empty_row()
                    row.update(status=START_FAILURE, message="%s: cannot read it: %s" % (task["input"], e.strerror or e))
                    yield key, row
                    continue
                self.futures[future.key] = (key, future)
                done.add(future)
            if not self.futures:
                continue
            future = next(done)
            key, _ = self.futures.pop(future.key)
            try:
                row = future.result()
            except Exception as e:  # lost more often than the retries allow, or the task itself failed
                row = _empty_row()
                row.update(status=CRASH, message=("the Dask task failed: %s: %s" % (type(e).__name__, e))[:MESSAGE_LIMIT])
            future.release()
            yield key, row

    def interrupt(self, run_id=None):
        try:
            self.client.cancel([f for _, f in self.futures.values()])
            if run_id:  # cancelling does not stop a task that runs: stop its converter
                self.client.run(stop_run, run_id, wait=True)
        except Exception:
            pass

    def close(self):
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


# --- the run ---------------------------------------------------------------------------------

def _size(path):
    try:
        return os.path.getsize(path)
    except OSError:
        return 0


def find_cli(cli=None):
    """The converter: `cli`, $SUBD2NURBS_CLI, or subd2nurbs on PATH."""
    cli = cli or os.environ.get("SUBD2NURBS_CLI") or shutil.which("subd2nurbs")
    if not cli:
        raise BatchError("cannot find the subd2nurbs command line: put it on PATH, set SUBD2NURBS_CLI or use --cli")
    return os.path.abspath(cli) if os.path.sep in cli else cli


def default_memory(workers):
    """The address-space limit per file: the machine's memory shared by the workers."""
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError):
        return 0
    return total // max(1, workers)


def _receive(outcome, row, outdir, remote):
    """Writes the output and report a worker sent back (outcome["files"], removed from it)
    atomically into `outdir`; on a remote cluster, checks that an output the worker wrote on the
    shared path is visible here."""
    files = outcome.pop("files", None)
    if files is not None:
        try:
            for kind in ("output", "report"):
                if kind in files:
                    path = os.path.join(outdir, row[kind])
                    os.makedirs(os.path.dirname(path), exist_ok=True)
                    _write_atomic(path, files[kind])
        except OSError as e:
            outcome.update(status=EXIT_CLASSES[3], exit_code=None,
                           message="cannot write what the worker sent back: %s" % e)
            return
    if outcome.get("status") == "ok":
        missing = [row[k] for k in ("output", "report") if not os.path.exists(os.path.join(outdir, row[k]))]
        if missing:
            outcome.update(status=NO_OUTPUT, message="%s: converted%s, but not here (the output folder is not "
                           "shared with the workers: let the inputs be sent, --send-inputs always)" % (
                               ", ".join(missing), " by a worker" if remote else ""))


def run(inputs, outdir, settings=None, scheduler=None, *, manifest=None, workers=None, dask_local=0,
        output_format="step", timeout=0, memory=None, retry_failed=False, force=False, cli=None, progress=None,
        quiet=True, send_inputs="auto", send_limit=SEND_LIMIT):
    """Converts every file of `inputs` (folders, searched recursively, or files) and of
    `manifest` (CSV or JSON) into `outdir`, mirroring the input tree, and writes
    outdir/summary.json and summary.csv. `settings`: {name: value} of docs/settings.md for every
    file (a manifest row overrides them). `scheduler`: a Dask scheduler address
    (``tcp://host:port``), or None for the local pool of `workers` processes (default: one per
    core); `dask_local`: a local Dask cluster of that many workers instead. `timeout` (s) and
    `memory` (bytes or "2G"; default the machine's memory / workers, none on a remote
    cluster; 0: no limit) bound each file. `send_inputs`: on a Dask cluster, "auto" sends the
    inputs up to `send_limit` bytes (or "8M") as bytes to a scheduler's workers (not to a
    --dask-local cluster, which shares this machine's files) and lets the workers read the larger
    ones from the client's path; "always" sends every input, "never" none; a sent input's output
    and report come back and are written here. Returns the :class:`Summary`. KeyboardInterrupt
    stops the converters, writes the summary of what is done (the rest "interrupted") and is
    raised again."""
    rows = settings_rows()
    if scheduler or dask_local:
        _import_distributed()  # before any work: says how to install it
    if send_inputs not in SEND_MODES:
        raise BatchError("send_inputs is one of %s, not %r" % (", ".join(SEND_MODES), send_inputs))
    send_limit = memory_bytes(send_limit)
    if output_format not in FORMATS:
        raise BatchError("unknown output format %r (%s)" % (output_format, ", ".join(FORMATS)))
    jobs = collect_jobs(inputs, settings, output_format, manifest, rows)
    cli = find_cli(cli)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if not workers:
        workers = cores
    # The threads of each converter unless the settings say (--threads): the cores shared by the
    # files converted at once, so that the batch's processes, not a converter's threads, keep the
    # cores busy (processes scale better: one conversion keeps about 1.45 of 2 cores busy). A
    # remote cluster's workers each run one file per worker thread: 1.
    if scheduler:
        file_threads = 1
    else:
        file_threads = max(1, cores // (dask_local or workers))
    if memory is None:  # a remote worker's converter keeps its own default (3/4 of its memory)
        memory = 0 if scheduler else default_memory(dask_local or workers)
    else:
        memory = memory_bytes(memory)
    os.makedirs(outdir, exist_ok=True)
    outdir = os.path.abspath(outdir)
    base_settings = normalized_settings(settings, rows)

    # The client's SOURCE_DATE_EPOCH (the STEP and IGES headers' dates) goes with every task:
    # a Dask worker's own environment need not have it.
    env = {k: os.environ[k] for k in ("SOURCE_DATE_EPOCH",) if k in os.environ}
    run_id = "%s-%d-%s" % (os.uname().nodename, os.getpid(), os.urandom(4).hex())

    _stopping.clear()
    previous = {} if force else _previous_rows(outdir)
    results = [None] * len(jobs)
    tasks = []
    for i, job in enumerate(jobs):
        args = settings_args(job.settings, rows)
        if "threads" not in job.settings:
            args += ["--threads", str(file_threads)]
        if memory and "max_memory" not in job.settings:
            args += ["--max-memory", str(memory * 3 // 4)]  # refused by estimate before the OS limit
        row = {"input": job.input, "output": job.output, "report": job.report, "status": None,
               "input_hash": file_hash(job.input) if os.path.isfile(job.input) else None,
               "settings_hash": settings_hash(job.settings, output_format)}
        if job.settings != base_settings:
            row["settings"] = job.settings
        prev = previous.get(job.output)
        if _resumable(prev, row, outdir, retry_failed):
            results[i] = dict(prev, input=job.input)
            continue
        results[i] = row
        if not (scheduler or dask_local) or send_inputs == "never":
            send = False
        elif send_inputs == "always":
            send = True
        else:
            send = bool(scheduler) and _size(job.input) <= send_limit
        tasks.append((i, {"cli": cli, "input": os.path.abspath(job.input),
                          "output": os.path.join(outdir, job.output), "report": os.path.join(outdir, job.report),
                          "args": args, "timeout": timeout, "memory": memory, "send": send,
                          "input_hash": row["input_hash"], "env": env, "run": run_id}))

    # Largest inputs first: a long conversion started last would leave the other workers idle.
    tasks.sort(key=lambda t: -_size(t[1]["input"]))
    skipped = len(jobs) - len(tasks)
    if progress is None:
        progress = Progress(len(jobs), quiet=quiet)
    progress.skipped(skipped)
    journal_path = os.path.join(outdir, JOURNAL)
    if not previous and os.path.exists(journal_path):
        os.remove(journal_path)
    backend = None
    interrupted = False
    try:
        if tasks:
            if scheduler or dask_local:
                backend = DaskBackend(scheduler, dask_local)
            else:
                backend = LocalPool(workers)
        with open(journal_path, "a", encoding="utf-8") as journal:
            try:
                for i, outcome in (backend.run(tasks) if backend else ()):
                    row = results[i]
                    _receive(outcome, row, outdir, backend.name == "dask" and scheduler)
                    row.update(outcome)
                    if row["status"] != INTERRUPTED:
                        journal.write(json.dumps(row) + "\n")
                        journal.flush()
                    progress.file(row["input"], row)
            except KeyboardInterrupt:
                interrupted = True
                if backend:
                    backend.interrupt(run_id)
    finally:
        progress.finish()
        for row in results:
            if row["status"] is None:
                row.update(status=INTERRUPTED, message="the batch was interrupted before this file")
        summary = Summary(results, base_settings, output_format, len(tasks) - sum(
            r["status"] == INTERRUPTED for r in results), skipped, interrupted,
            backend.name if backend else "none")
        summary.write(outdir)
        if not interrupted:
            try:
                os.remove(journal_path)
            except OSError:
                pass
        if backend:
            try:
                backend.close()
            except Exception:
                pass
    if interrupted:
        raise KeyboardInterrupt
    return summary


# --- the command line ------------------------------------------------------------------------

def _parser(rows):
    p = argparse.ArgumentParser(
        prog="subd2nurbs-batch",
        description="Convert a library of cages and meshes with subd2nurbs convert, each file in a process of "
                    "its own with a time and memory limit; writes OUTDIR/summary.json and summary.csv.",
        epilog="Exit codes: 0 every file converted, 1 usage error, 2 some files failed (see the summary), "
               "130 interrupted (run again to resume). `subd2nurbs-batch --dask-env` prints the environment "
               "(quieter Dask monitors) to start dask-scheduler and dask-worker with.")
    p.add_argument("inputs", nargs="*", metavar="INPUT", help="folders (searched recursively for %s) or files"
                   % " ".join(EXTENSIONS))
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR", help="output folder (mirrors the input tree)")
    p.add_argument("--manifest", metavar="FILE", help="CSV or JSON list: input, output, per-file settings")
    p.add_argument("--format", default="step", choices=FORMATS, help="output format (default step)")
    p.add_argument("--workers", type=int, metavar="N", help="local converter processes (default: one per core)")
    p.add_argument("--timeout", type=float, default=0, metavar="S", help="wall-time limit per file (0: none)")
    p.add_argument("--memory-limit", metavar="SIZE",
                   help="address-space limit per file, e.g. 4G (default: the machine's memory / workers; none with "
                        "--scheduler; 0: none)")
    p.add_argument("--retry-failed", action="store_true", help="convert again the files that failed last time")
    p.add_argument("--force", action="store_true", help="convert every file, ignoring the last run")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run on this Dask scheduler's workers")
    p.add_argument("--dask-local", type=int, default=0, metavar="N", help="run on a local Dask cluster of N workers")
    p.add_argument("--send-inputs", choices=SEND_MODES, default="auto",
                   help="on a Dask cluster: send the inputs to the workers as bytes (and get the outputs back) instead "
                        "of a shared path; auto (default): those up to --send-limit on a --scheduler cluster")
    p.add_argument("--send-limit", default="8M", metavar="SIZE",
                   help="the largest input sent as bytes with --send-inputs auto (default 8M)")
    p.add_argument("--cli", metavar="PATH", help="the subd2nurbs command line (default $SUBD2NURBS_CLI or PATH)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    g = p.add_argument_group("conversion settings (those of subd2nurbs convert, docs/settings.md)")
    for name, row in rows.items():
        if row["type"] == "flag":
            g.add_argument(row["cli"], dest="setting_" + name, action="store_true", help=row["help"])
        else:
            g.add_argument(row["cli"], dest="setting_" + name, metavar="VALUE", help=row["help"])
    return p


def _stop_on_signal(signum, frame):
    raise KeyboardInterrupt


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv == ["--dask-env"]:  # for the shell that starts dask-scheduler / dask-worker
        for name, value in dask_environment().items():
            print("export %s=%s" % (name, value))
        return 0
    try:
        rows = settings_rows()
    except ImportError as e:
        sys.stderr.write("subd2nurbs-batch: cannot load the subd2nurbs module: %s\n" % e)
        return 1
    args = _parser(rows).parse_args(argv)
    signal.signal(signal.SIGTERM, _stop_on_signal)  # as Ctrl-C: stop the converters, write the summary
    settings = {name: getattr(args, "setting_" + name) for name in rows}
    settings = {k: v for k, v in settings.items() if v not in (None, False)}
    if args.scheduler and args.dask_local:
        sys.stderr.write("subd2nurbs-batch: --scheduler and --dask-local exclude each other\n")
        return 1
    if not args.inputs and not args.manifest:
        sys.stderr.write("subd2nurbs-batch: no input: give folders or files, or --manifest\n")
        return 1
    try:
        summary = run(args.inputs, args.output, settings, args.scheduler, manifest=args.manifest,
                      workers=args.workers, dask_local=args.dask_local, output_format=args.format,
                      timeout=args.timeout, memory=args.memory_limit, retry_failed=args.retry_failed,
                      force=args.force, cli=args.cli, quiet=args.quiet, send_inputs=args.send_inputs,
                      send_limit=args.send_limit)
    except BatchError as e:
        sys.stderr.write("subd2nurbs-batch: %s\n" % e)
        return 1
    except KeyboardInterrupt:
        sys.stderr.write("subd2nurbs-batch: interrupted; the summary lists what is done; run the same command "
                         "again to convert the rest\n")
        return 130
    if not args.quiet:
        sys.stderr.write("subd2nurbs-batch: %d files: %s; %d converted, %d skipped; summary in %s\n" % (
            len(summary.files), ", ".join("%d %s" % (n, s) for s, n in sorted(summary.counts.items())),
            summary.converted, summary.skipped, os.path.join(args.output, "summary.json")))
    return 0 if summary.failed == 0 else 2


if __name__ == "__main__":
    # Through the package's module, not __main__: Dask pickles convert_one by its module name.
    from subd2nurbs.batch import main as _main
    sys.exit(_main())
