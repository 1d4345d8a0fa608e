# Runs test_workbench.py inside freecadcmd and exits with its result (a plain freecadcmd
# script argument exits 0 even when the script fails; os._exit is honoured).
# Run as: freecadcmd -c "exec(open('run_workbench_tests.py').read())" with S2N_TEST_DIR,
# S2N_PYTHONPATH (build/python:freecad_plugin), S2N_CLI and S2N_CORPUS set.
import os
import sys
import traceback
import unittest

try:
    for p in reversed(os.environ["S2N_PYTHONPATH"].split(os.pathsep) + [os.environ["S2N_TEST_DIR"]]):
        sys.path.insert(0, p)
    import test_workbench
    suite = unittest.defaultTestLoader.loadTestsFromModule(test_workbench)
    result = unittest.TextTestRunner(stream=sys.stderr, verbosity=2).run(suite)
    ok = result.wasSuccessful() and result.testsRun > 0 and not result.skipped
except BaseException:
    traceback.print_exc()
    ok = False
sys.stderr.flush()
sys.stdout.flush()
os._exit(0 if ok else 1)
