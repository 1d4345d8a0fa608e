#!/usr/bin/env python3
"""Runs the hostile corpus (scripts/make_hostile_corpus.py) through one command of the CLI or
through the Python module, and checks every run:

* the exit code the manifest expects (never 4 for bad input) and its message (a regular
  expression) on stderr;
* the message is bounded (no multi-megabyte echo) and has no raw control bytes except
  newlines and tabs; `info` never prints nan / inf;
* the outputs are untouched on failure: an existing output file (filled with a sentinel)
  keeps its content, no new file appears in the output directory (no temporary left over),
  and a successful run replaces exactly the outputs it was asked for;
* time and memory are bounded: each run has a wall-clock timeout and an address-space limit
  (RLIMIT_AS; not under AddressSanitizer, whose shadow memory needs more address space; the
  timeout is 5x longer there).

    run_hostile.py --corpus DIR --command info|convert|refine|limit|python|signal
                   [--cli build/subd2nurbs] [--python-path build/python]
                   [--timeout S] [--memory-mb M]

Exit code 0 when every case passed; the failures are listed otherwise.
"""
import argparse
import json
import os
import re
import resource
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time

SENTINEL = b"sentinel: this file must not change\n"

PYTHON_RUNNER = r"""
import sys, json
sys.path.insert(0, sys.argv[1])
import subd2nurbs as s2n
kwargs = json.loads(sys.argv[3])
try:
    cage = s2n.read_cage(sys.argv[2])
    r = s2n.convert(cage, **kwargs)
    print("ok", r.num_patches)
    sys.exit(0)
except s2n.CageError as e:
    sys.stderr.write("CageError: %s\n" % e)
    sys.exit(2)
except s2n.SettingsError as e:
    sys.stderr.write("SettingsError: %s\n" % e)
    sys.exit(1)
except s2n.ConversionError as e:
    sys.stderr.write("ConversionError: %s\n" % e)
    sys.exit(4)
except MemoryError as e:
    sys.stderr.write("MemoryError: %s\n" % e)
    sys.exit(4)
"""


def limit_memory(megabytes):
    def apply():
        if megabytes > 0:
            resource.setrlimit(resource.RLIMIT_AS, (megabytes << 20, megabytes << 20))
    return apply


class Runner:
    def __init__(self, args):
        self.args = args
        self.corpus = os.path.abspath(args.corpus)
        self.cli = os.path.abspath(args.cli) if args.cli else None
        self.failures = []
        self.runs = 0
        self.slowest = (0.0, "")
        asan = "asan" in os.environ.get("LD_PRELOAD", "") or os.environ.get("SUBD2NURBS_SANITIZED") == "1"
        self.asan = asan
        self.memory_mb = 0 if asan else args.memory_mb
        # Instrumented binaries are several times slower (with full malloc stacks, as
        # scripts/sanitize.sh runs the tests that load OCCT, up to 10x): the bound scales.
        self.timeout = args.timeout * (5 if asan else 1)

    def fail(self, case, why):
        self.failures.append("%s [%s]: %s" % (case["name"], self.args.command, why))

    def run(self, argv, cwd, case):
        t0 = time.monotonic()
        try:
            p = subprocess.run(argv, cwd=cwd, stdin=subprocess.DEVNULL, capture_output=True,
                               timeout=self.timeout, preexec_fn=limit_memory(self.memory_mb))
        except subprocess.TimeoutExpired:
            self.fail(case, "no answer within %d s (blocked or unbounded work)" % self.timeout)
            return None
        dt = time.monotonic() - t0
        self.runs += 1
        if dt > self.slowest[0]:
            self.slowest = (dt, case["name"])
        return p

    def check_streams(self, case, p, expect):
        err = p.stderr
        limit = expect.get("max_output", 20000)
        if len(err) > limit or len(p.stdout) > max(limit, 200000):
            self.fail(case, "output too long (%d bytes on stderr, %d on stdout)" % (len(err), len(p.stdout)))
        bad = [b for b in err if b < 0x20 and b not in (0x0a, 0x09)]
        if bad:
            self.fail(case, "raw control byte(s) %r in stderr" % sorted(set(bad))[:5])
        text = err.decode("utf-8", "replace")
        code = expect.get("exit")
        if p.returncode == 4 or p.returncode < 0:
            self.fail(case, "exit %d (internal error / killed) for input: %s" % (p.returncode, text[-500:]))
        elif code is not None and p.returncode != code:
            self.fail(case, "exit %d, expected %d: %s" % (p.returncode, code, text[-500:]))
        if expect.get("message") and not re.search(expect["message"], text, re.S):
            self.fail(case, "stderr does not match /%s/: %s" % (expect["message"], text[-500:]))
        if expect.get("stdout") and not re.search(expect["stdout"], p.stdout.decode("utf-8", "replace")):
            self.fail(case, "stdout does not match /%s/" % expect["stdout"])
        return text

    def input_path(self, case):
        path = case["path"]
        return path if os.path.isabs(path) else os.path.join(self.corpus, path)

    def expectation(self, case, command):
        e = case["expect"]
        return e.get(command, e.get("default"))

    # --- commands -------------------------------------------------------------------------

    def case_info(self, case, work):
        expect = self.expectation(case, "info")
        p = self.run([self.cli, "info", self.input_path(case)], work, case)
        if p is None:
            return
        self.check_streams(case, p, expect)
        if any(b < 0x20 and b not in (0x0a, 0x09) for b in p.stdout):
            self.fail(case, "raw control byte(s) in info's output")
        out = p.stdout.decode("utf-8", "replace").lower()
        if re.search(r"\bnan\b|\binf\b", out):
            self.fail(case, "info printed nan / inf")
        p = self.run([self.cli, "info", "--json", self.input_path(case)], work, case)
        if p is not None and p.returncode == 0:
            try:
                json.loads(p.stdout)
            except ValueError as e:
                self.fail(case, "info --json is not JSON: %s" % e)

    def outputs_for(self, command, work):
        if command == "convert":
            return {"-o": os.path.join(work, "out.step"), "--report": os.path.join(work, "report.json")}
        return {"-o": os.path.join(work, "out.obj")}

    def case_writer(self, case, work, command):
        expect = self.expectation(case, command)
        if expect is None:
            return
        outputs = self.outputs_for(command, work)
        for path in outputs.values():
            with open(path, "wb") as f:
                f.write(SENTINEL)
        before = sorted(os.listdir(work))
        argv = [self.cli, command, self.input_path(case)]
        for option, path in outputs.items():
            argv += [option, path]
        argv += case["args"].get(command, ["-l", "1"] if command == "refine" else [])
        if command == "convert" and "--quiet" not in argv:
            argv.append("--quiet")
        if command == "convert" and self.asan and "--max-memory" not in argv:
            # Without the address-space limit the memory guard would follow the machine's
            # memory; the limit the process would have seen (3/4 of it) is given explicitly.
            argv += ["--max-memory", "%dM" % (self.args.memory_mb * 3 // 4)]
        p = self.run(argv, work, case)
        if p is None:
            return
        self.check_streams(case, p, expect)
        self.check_outputs(case, work, before, outputs, p.returncode == 0)

    def check_outputs(self, case, work, before, outputs, success):
        after = sorted(os.listdir(work))
        if after != before:
            self.fail(case, "files appeared or vanished in the output directory: %s -> %s" % (before, after))
        for option, path in outputs.items():
            if not os.path.exists(path):
                self.fail(case, "%s %s vanished" % (option, path))
                continue
            with open(path, "rb") as f:
                content = f.read(len(SENTINEL) + 1)
            if success and content == SENTINEL:
                self.fail(case, "%s was not written by a successful run" % option)
            if not success and content != SENTINEL:
                self.fail(case, "%s was changed by a failed run" % option)

    def case_limit(self, case, work):
        if case["kind"] == "queries":
            mesh = os.path.join(self.corpus, "cube_target.obj")
            queries = self.input_path(case)
        else:
            mesh = self.input_path(case)
            queries = os.path.join(work, "queries.txt")
            with open(queries, "w") as f:
                f.write("0 0 0.5 0.5\n")
        expect = self.expectation(case, "limit")
        p = self.run([self.cli, "limit", mesh, queries], work, case)
        if p is not None:
            self.check_streams(case, p, expect)
            if p.returncode != 0 and p.stdout:
                self.fail(case, "a failed limit run printed results")

    def case_python(self, case, work):
        expect = self.expectation(case, "python")
        kwargs = case["args"].get("python", {})
        p = self.run([sys.executable, "-c", PYTHON_RUNNER, os.path.abspath(self.args.python_path),
                      self.input_path(case), json.dumps(kwargs)], work, case)
        if p is not None:
            if p.returncode == 1 and b"Traceback" in p.stderr:
                self.fail(case, "an unexpected Python exception: %s" % p.stderr.decode("utf-8", "replace")[-800:])
                return
            # The module's messages are the CLI's without "error: " after the location.
            expect = dict(expect, message=expect.get("message", "").replace("error: ", ""))
            self.check_streams(case, p, expect)

    # --- outputs that are special ------------------------------------------------------------

    def case_output(self, case, work, command):
        setup = case["kind"].split(":", 1)[1]
        expect = self.expectation(case, command)
        source = os.path.join(self.corpus, "cube_target.obj")
        mesh = os.path.join(work, "in.obj")
        shutil.copy(source, mesh)
        ext = ".step" if command == "convert" else ".obj"
        out = os.path.join(work, "out" + ext)
        extra = []
        sentinel_files = [mesh]
        target = None
        if setup == "input":
            if command == "convert":
                return  # convert cannot write .obj: covered by refine
            out = mesh
        elif setup == "hardlink":
            if command == "convert":
                return
            out = os.path.join(work, "link.obj")
            os.link(mesh, out)
        elif setup == "fifo":
            out = os.path.join(work, "pipe" + ext)
            os.mkfifo(out)
        elif setup == "directory":
            out = os.path.join(work, "dir" + ext)
            os.mkdir(out)
        elif setup == "devnull":
            # convert needs an extension: a symbolic link to the device (followed, then refused).
            out = "/dev/null" if command == "refine" else os.path.join(work, "null" + ext)
            if command != "refine":
                os.symlink("/dev/null", out)
        elif setup == "dangling":
            out = os.path.join(work, "dangling" + ext)
            os.symlink(os.path.join(work, "nowhere", "x" + ext), out)
        elif setup == "missingdir":
            out = os.path.join(work, "nowhere", "out" + ext)
        elif setup == "symlink":
            target = os.path.join(work, "target" + ext)
            with open(target, "wb") as f:
                f.write(SENTINEL)
            out = os.path.join(work, "link" + ext)
            os.symlink(target, out)
        elif setup in ("report_same", "report_missingdir", "preview_input"):
            if command != "convert":
                return
            with open(out, "wb") as f:
                f.write(SENTINEL)
            sentinel_files.append(out)
            if setup == "report_same":
                extra = ["--report", out]
            elif setup == "report_missingdir":
                extra = ["--report", os.path.join(work, "nowhere", "r.json")]
            else:
                extra = ["--preview", mesh]
        with open(mesh, "rb") as f:
            mesh_before = f.read()
        before = sorted(os.listdir(work))
        argv = [self.cli, command, mesh, "-o", out] + extra + (["-l", "1"] if command == "refine" else ["--quiet"])
        p = self.run(argv, work, case)
        if p is None:
            return
        self.check_streams(case, p, expect)
        with open(mesh, "rb") as f:
            if f.read() != mesh_before:
                self.fail(case, "the input file was changed")
        for path in sentinel_files[1:]:
            with open(path, "rb") as f:
                if f.read() != SENTINEL:
                    self.fail(case, "%s was changed by a failed run" % path)
        after = sorted(os.listdir(work))
        if after != before:
            self.fail(case, "files appeared or vanished: %s -> %s" % (before, after))
        if setup == "symlink" and p.returncode == 0:
            if not os.path.islink(out):
                self.fail(case, "the symbolic link was replaced by a file")
            with open(target, "rb") as f:
                if f.read() == SENTINEL:
                    self.fail(case, "the link's target was not written")
        if setup == "devnull" and not stat.S_ISCHR(os.stat("/dev/null").st_mode):
            self.fail(case, "/dev/null was replaced")

    # --- SIGTERM / SIGINT during a run ---------------------------------------------------------

    def case_signal(self):
        """A conversion with a report is stopped by SIGTERM, SIGINT and SIGHUP at two known stages
        (the CLI's test hook SUBD2NURBS_TEST_STOP: "output", the main output staged and the report
        not yet; "commit", every output staged and none renamed): it must end by the signal and
        leave no file. The run says on stderr when it reaches the stage and waits there for the
        signal, so the outcome does not depend on the machine's load. A control run with the
        cleanup disabled (SUBD2NURBS_TEST_NO_SIGNAL_CLEANUP) must leave its temporary files: the
        check can fail."""
        grid = os.path.join(self.corpus, "grid_10.obj")
        for stage in ("output", "commit"):
            for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
                case = {"name": "signal_%s_at_%s" % (sig.name, stage), "expect": {}}
                outcome = self.signal_run(grid, sig, stage, cleanup=True)
                if outcome != "ok":
                    self.fail(case, outcome)
            case = {"name": "signal_control_without_cleanup_at_%s" % stage, "expect": {}}
            outcome = self.signal_run(grid, signal.SIGTERM, stage, cleanup=False)
            if not outcome.startswith("files left after the signal: ['.out.brep."):
                self.fail(case, "the run without the cleanup should leave its temporary files, got: " + outcome)

    def signal_run(self, grid, sig, stage, cleanup):
        """One run of case_signal: "ok", or what went wrong."""
        work = tempfile.mkdtemp(prefix="s2n_signal_")
        try:
            argv = [self.cli, "convert", grid, "-o", os.path.join(work, "out.brep"), "--report",
                    os.path.join(work, "r.json"), "--quiet"]
            env = dict(os.environ, SUBD2NURBS_TEST_STOP=stage)
            if not cleanup:
                env["SUBD2NURBS_TEST_NO_SIGNAL_CLEANUP"] = "1"
            p = subprocess.Popen(argv, cwd=work, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                 preexec_fn=limit_memory(self.memory_mb), env=env)
            stopped = False
            try:
                # The hook's line is the last the run prints before it waits (--quiet).
                for line in iter(p.stderr.readline, b""):
                    if line.startswith(b"subd2nurbs: test stop: " + stage.encode()):
                        stopped = True
                        break
                if stopped:
                    p.send_signal(sig)
                p.stderr.read()
                p.wait(timeout=self.timeout * 4)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
                return "did not end after the signal"
            self.runs += 1
            left = sorted(os.listdir(work))
            if not stopped:
                return "never reached the stage %r (exit %s, files %s)" % (stage, p.returncode, left)
            if p.returncode != -sig:
                return "ended with %s, not by the signal" % p.returncode
            if left:
                return "files left after the signal: %s" % left
            return "ok"
        finally:
            shutil.rmtree(work, ignore_errors=True)

    def main(self):
        with open(os.path.join(self.corpus, "manifest.json")) as f:
            cases = json.load(f)["cases"]
        command = self.args.command
        if command == "signal":
            self.case_signal()
        for case in cases if command != "signal" else []:
            skip = case["args"].get("skip", [])
            if command in skip:
                continue
            if case["kind"] == "queries" and command != "limit":
                continue
            if case["kind"] == "signal":
                continue
            if case["kind"].startswith("output:") and command not in ("convert", "refine"):
                continue
            work = tempfile.mkdtemp(prefix="s2n_hostile_")
            try:
                if case["kind"].startswith("output:"):
                    self.case_output(case, work, command)
                elif command == "info":
                    self.case_info(case, work)
                elif command in ("convert", "refine"):
                    self.case_writer(case, work, command)
                elif command == "limit":
                    self.case_limit(case, work)
                elif command == "python":
                    self.case_python(case, work)
            finally:
                shutil.rmtree(work, ignore_errors=True)
        print("%s: %d runs, %d failures; slowest %.2f s (%s)" % (command, self.runs, len(self.failures),
                                                                 self.slowest[0], self.slowest[1]))
        for f in self.failures:
            print("FAIL " + f)
        return 1 if self.failures or self.runs == 0 else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--corpus", required=True)
    ap.add_argument("--command", required=True, choices=["info", "convert", "refine", "limit", "python", "signal"])
    ap.add_argument("--cli")
    ap.add_argument("--python-path", default="build/python")
    ap.add_argument("--timeout", type=float, default=60)
    ap.add_argument("--memory-mb", type=int, default=4096)
    return Runner(ap.parse_args()).main()


if __name__ == "__main__":
    sys.exit(main())
