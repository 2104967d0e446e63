"""viscobar from Python: the Petrov-Schatzman scheme for viscoelastic bodies with unilateral
contact, run in memory, its outputs as numpy arrays.

    >>> import viscobar
    >>> run = viscobar.run("impact", set={"time.step": 0.005})
    >>> run.history["energy"][-1]          # history.csv's column, one value per step
    >>> run.displacement.shape             # (kept steps, nodes)
    >>> run.write("out/impact")            # the command line's files

``run`` takes a built-in name (``scenes()``), a path to a TOML scene file, TOML text or a
dict with the TOML's structure; ``set`` has the meaning of the command line's ``--set``.
The arrays hold the numbers of the files ``viscobar run`` writes for the same scene, bit for
bit. A scene that cannot be run raises ``SceneError`` (a ``ValueError``), a failed run
``RunError`` (a ``RuntimeError``), each with the command line's message.
"""

from ._viscobar import (
    Run,
    RunError,
    SceneError,
    __version__,
    _library_run_seconds,
    _panic_for_test,
    run,
    scenes,
    show,
)

__all__ = ["Run", "RunError", "SceneError", "run", "scenes", "show", "__version__"]
