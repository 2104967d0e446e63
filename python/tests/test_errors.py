"""Every documented error: `SceneError` (a ValueError) with the command line's exit-2
message naming the key, `RunError` (a RuntimeError) with its exit-1 message naming the step,
and a Rust panic turned into `RunError`."""

import pytest

import viscobar
from conftest import cli

#: Scenes refused as written: the `run` arguments, as `viscobar.run`'s keywords and as the
#: command line's, and what the message names.
SCENE_ERRORS = {
    "unknown scene": (("no-such-scene",), {}, ["no-such-scene"], "no-such-scene"),
    "value out of range": (("impact",), {"set": {"time.step": -0.01}},
                           ["impact", "--set", "time.step=-0.01"], "`time.step`"),
    "unknown key": (("impact",), {"set": {"bar.stiffness": 2.0}},
                    ["impact", "--set", "bar.stiffness=2.0"], "stiffness"),
    "key without a section": (("impact",), {"set": {"time": 1.0}},
                              ["impact", "--set", "time=1.0"], "--set time=1.0"),
    "bad expression": (("impact",), {"set": {"initial.velocity": "-1 +* x"}},
                       ["impact", "--set", "initial.velocity=-1 +* x"], "`initial.velocity`"),
    "unknown solver": (("impact",), {"solver": "nope"}, ["impact", "--solver", "nope"],
                       "`solver.method`"),
    "solver setting": (("impact",), {"solver": "osqp", "set": {"solver.max_iter": 0}},
                       ["impact", "--set", "solver.max_iter=0", "--solver", "osqp"],
                       "`solver.max_iter`"),
    "plane key on a bar": (("plane-strip",), {"set": {"heat.coupling": 0.1}},
                           ["plane-strip", "--set", "heat.coupling=0.1"], "`heat`"),
}


@pytest.mark.parametrize("case", SCENE_ERRORS)
def test_scene_errors_carry_the_cli_message_naming_the_key(case, tmp_path):
    args, kwargs, cli_args, key = SCENE_ERRORS[case]
    with pytest.raises(viscobar.SceneError) as raised:
        viscobar.run(*args, **kwargs)
    message = str(raised.value)
    assert key in message, message
    done = cli("run", *cli_args, "--out", str(tmp_path / "out"))
    assert done.returncode == 2, done.stderr
    assert done.stderr == f"error: {message}\n"
    assert isinstance(raised.value, ValueError)


def test_scene_errors_of_the_python_forms_name_the_key():
    with pytest.raises(viscobar.SceneError, match="`mesh.elements` = 0"):
        scene = {**__import__("tomllib").loads(viscobar.show("impact")), "mesh": {"elements": 0}}
        viscobar.run(scene)
    with pytest.raises(viscobar.SceneError, match="`time.step` = .*no TOML form"):
        viscobar.run("impact", set={"time.step": object()})
    with pytest.raises(viscobar.SceneError, match="scene is not valid"):
        viscobar.run("[bar]\nlength = \n")
    with pytest.raises(viscobar.SceneError, match="not int"):
        viscobar.run(3)
    with pytest.raises(viscobar.SceneError, match="unknown scene `nope`") as raised:
        viscobar.show("nope")
    assert raised.value.args[0] == cli("show", "nope").stderr.removeprefix("error: ").rstrip()


def test_a_failed_step_is_a_run_error_naming_the_step(tmp_path):
    overrides = {"load.density": "1e300*t*t"}
    with pytest.raises(viscobar.RunError) as raised:
        viscobar.run("impact", set=overrides)
    message = str(raised.value)
    assert "step 2" in message and "exact" in message, message
    assert isinstance(raised.value, RuntimeError)
    done = cli("run", "impact", "--set", "load.density=1e300*t*t", "--out", str(tmp_path))
    assert done.returncode == 1
    assert done.stderr == f"error: {message}\n"


def test_a_write_that_fails_is_a_run_error_naming_the_path(tmp_path):
    run = viscobar.run("impact", set={"time.end": 0.1})
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(viscobar.RunError, match="cannot write .*file"):
        run.write(blocker / "out")
    assert blocker.read_text() == "not a folder"


def test_a_panic_becomes_a_run_error():
    with pytest.raises(viscobar.RunError, match="internal error .*panic.*_panic_for_test"):
        viscobar._panic_for_test()
    # The module still works after it.
    assert viscobar.run("impact", set={"time.end": 0.1}).summary["steps"] == 10
