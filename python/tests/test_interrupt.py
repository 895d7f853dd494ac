"""Ctrl-C stops a run cleanly: KeyboardInterrupt, no partial folder, and the
interpreter goes on."""

import os
import signal
import subprocess
import sys
import textwrap

from conftest import ROOT

# A run whose every evaluation takes 50 ms and says so, to be interrupted.
SLOW_RUN = textwrap.dedent("""
    import json, sys, time
    import numpy as np
    import spec2fab

    class Slow(spec2fab.Metric):
        compares = "albedo"
        def error(self, simulated, target):
            print("evaluating", flush=True)
            time.sleep(0.05)
            return float(np.mean((simulated - target) ** 2))

    spec2fab.register(Slow, "slow")
    experiment = json.load(open("datasets/experiments/colour_patches_box.json"))
    for tuner in experiment["goal"]["tuners"]:
        tuner["metric"] = {"type": "slow"}

    def slow_run():
        try:
            spec2fab.run(experiment, out=sys.argv[1], threads=1, origin="datasets/experiments/colour_patches_box.json")
        except KeyboardInterrupt as stopped:
            print("stopped:", type(stopped).__name__, stopped, flush=True)
""")


def interrupted(script, out):
    """Runs `script` (argv[1] = out), sends SIGINT once it has evaluated
    once, and returns what it printed."""
    process = subprocess.Popen([sys.executable, "-c", script, str(out)], cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=os.environ.copy())
    assert process.stdout.readline().strip() == "evaluating"
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 0, stderr
    return stdout


def test_ctrl_c_stops_the_run_and_leaves_nothing(tmp_path):
    stdout = interrupted(SLOW_RUN + textwrap.dedent("""
        slow_run()
        print("after:", spec2fab.simulate("albedo", "datasets/simulations/albedo_cyan_over_white.json").shape)
    """), tmp_path / "run")
    assert "stopped: Stopped stopped on request (Ctrl-C)" in stdout
    assert "after: (3,)" in stdout
    assert [p.name for p in tmp_path.iterdir()] == []  # no partial folder either


def test_a_problem_made_before_a_ctrl_c_still_evaluates_after_it(tmp_path):
    stdout = interrupted(SLOW_RUN + textwrap.dedent("""
        before = spec2fab.tuner_problem("datasets/experiments/colour_patches_box.json", tuner="sky")
        slow_run()
        print("after:", before([1.0, 0.027]) >= 0)
    """), tmp_path / "run")
    assert "stopped: Stopped" in stdout and "after: True" in stdout


def test_ctrl_c_stops_the_bench_and_leaves_no_report(tmp_path):
    stdout = interrupted(textwrap.dedent("""
        import sys, time
        import spec2fab

        class Slow(spec2fab.Optimizer):
            stochastic = True
            def minimize(self, problem, x, seed):
                while True:
                    print("evaluating", flush=True)
                    time.sleep(0.05)
                    problem(x)

        spec2fab.register(Slow, "slow")
        try:
            spec2fab.bench(problems=["albedo_column"], optimizers=["slow"], seeds=50, budget="100d",
                           out=sys.argv[1], threads=1)
        except KeyboardInterrupt as stopped:
            print("stopped:", type(stopped).__name__, flush=True)
    """), tmp_path / "bench")
    assert "stopped: Stopped" in stdout
    assert [p.name for p in tmp_path.iterdir()] == []
