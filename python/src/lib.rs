//! The extension module `viscobar._viscobar`, re-exported by the Python package `viscobar`
//! (`python/viscobar/__init__.py`): scenes read as the command line reads them, runs kept in
//! memory by [`viscobar::output::memory`] with the GIL released, their outputs as numpy arrays
//! holding the numbers of the command line's files, and errors as `SceneError` (the exit-2
//! messages) and `RunError` (exit 1; a Rust panic too, caught before it reaches Python).
//!
//! Python's documentation of every name is the docstrings here and in `__init__.py`.

mod convert;

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::mem::take;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use viscobar::output::memory::{Recorded, record_any};
use viscobar::output::{run_plane_to_dir, run_to_dir};
use viscobar::scene::{self, AnyScene};

pyo3::create_exception!(
    viscobar,
    SceneError,
    PyValueError,
    "A scene that cannot be run as written: the message is the command line's (exit code 2) \
     and names the key at fault."
);
pyo3::create_exception!(
    viscobar,
    RunError,
    PyRuntimeError,
    "A run that failed: the message is the command line's (exit code 1) and names the step; \
     an internal error (a Rust panic) is raised as this too."
);

/// A failure of the library, before it becomes a Python exception.
enum Failure {
    Run(viscobar::RunError),
    Panic(String),
}

impl From<viscobar::RunError> for Failure {
    fn from(e: viscobar::RunError) -> Self {
        Failure::Run(e)
    }
}

impl From<viscobar::SceneError> for Failure {
    fn from(e: viscobar::SceneError) -> Self {
        Failure::Run(e.into())
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> Self {
        match f {
            Failure::Run(viscobar::RunError::Scene(e)) => SceneError::new_err(e.to_string()),
            Failure::Run(e) => RunError::new_err(e.to_string()),
            Failure::Panic(message) => RunError::new_err(format!(
                "internal error (a panic in viscobar, please report it): {message}"
            )),
        }
    }
}

/// Runs `work` with the GIL released, a panic caught and returned as [`Failure::Panic`].
fn detached<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, Failure> + Send,
) -> Result<T, Failure> {
    py.detach(|| {
        catch_unwind(AssertUnwindSafe(work)).unwrap_or_else(|payload| {
            let message = (payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".into());
            Err(Failure::Panic(message))
        })
    })
}

/// The names of the built-in scenes, bar (with and without a temperature) and plane.
#[pyfunction]
fn scenes() -> Vec<&'static str> {
    let mut names = scene::builtin_names();
    names.extend(scene::thermal_builtin_names());
    names.extend(scene::plane::PLANE_BUILTIN.iter().map(|(n, _)| *n));
    names
}

/// The TOML text of the built-in scene `name`, as `viscobar show NAME` prints it.
#[pyfunction]
fn show(name: &str) -> PyResult<&'static str> {
    scene::builtin_text(name)
        .or_else(|| scene::plane::plane_builtin_text(name))
        .ok_or_else(|| {
            SceneError::new_err(format!(
                "unknown scene `{name}` (built-in scenes: {})",
                scenes().join(", ")
            ))
        })
}

/// Runs a scene in memory and returns its outputs as a `Run`; no file is written.
///
/// `scene` is a built-in name (`viscobar.scenes()`), the path of a TOML scene file (a str or
/// an `os.PathLike`), TOML text, or a dict with the TOML's structure. `solver` overrides
/// `[solver] method` (`"exact"`, `"osqp"`, `"penalty"`); `set` maps keys to values as the
/// command line's `--set KEY=VALUE` does (`{"time.step": 0.005, "edges.bottom.gap": 0.1}`;
/// a str value is read as `--set` reads its text: TOML if it parses, else a string). The
/// steps run with the GIL released, so runs in threads go in parallel.
///
/// Raises `SceneError` for a scene that cannot be run as written and `RunError` for a run
/// that fails, each with the command line's message.
#[pyfunction]
#[pyo3(signature = (scene, *, solver=None, set=None))]
fn run(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    solver: Option<&str>,
    set: Option<&Bound<'_, PyDict>>,
) -> PyResult<Run> {
    let source = convert::Source::new(scene, set, solver)?;
    let (name, any, recorded) = detached(py, || {
        let (name, any) = source.load()?;
        let recorded = record_any(&name, &any)?;
        Ok((name, any, recorded))
    })?;
    Run::new(py, name, any, recorded)
}

/// Raises the error a panic in the library raises (`RunError`): a test hook, not part of the
/// API.
#[pyfunction]
fn _panic_for_test(py: Python<'_>) -> PyResult<()> {
    detached(py, || -> Result<(), Failure> {
        panic!("viscobar._panic_for_test");
    })?;
    Ok(())
}

/// Seconds the library takes to read and run `scene` in memory, timed in Rust with the GIL
/// released (python/bench/ratio.py's reference; not part of the API). `keep = "outputs"` keeps
/// what `run` keeps (`viscobar::output::memory`); `keep = "records"` is the library's
/// `run_in_memory` (every step's record, no profiles).
#[pyfunction]
#[pyo3(signature = (scene, *, set=None, keep="outputs"))]
fn _library_run_seconds(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    set: Option<&Bound<'_, PyDict>>,
    keep: &str,
) -> PyResult<f64> {
    let source = convert::Source::new(scene, set, None)?;
    let records = match keep {
        "outputs" => false,
        "records" => true,
        _ => return Err(PyValueError::new_err("keep is \"outputs\" or \"records\"")),
    };
    let seconds = detached(py, || {
        let start = std::time::Instant::now();
        let (name, any) = source.load()?;
        match (&any, records) {
            (_, false) => drop(record_any(&name, &any)?),
            (AnyScene::Bar(bar), true) => drop(viscobar::run_in_memory(&name, bar)?),
            (AnyScene::Plane(plane), true) => drop(viscobar::run_plane_in_memory(&name, plane)?),
        }
        Ok(start.elapsed().as_secs_f64())
    })?;
    Ok(seconds)
}

/// A finished run: its summary, history and kept profiles, as the command line writes them.
///
/// The arrays hold the numbers of the command line's files for the same scene and `[output]`
/// keys, bit for bit: `times` and `positions` rounded to 12 significant digits as the files
/// write them, every other value exactly. They are read-only.
#[pyclass(frozen, module = "viscobar")]
struct Run {
    name: String,
    /// The run's outputs, its profile arrays and history columns moved into numpy's.
    recorded: Recorded,
    scene: AnyScene,
    times: Py<PyAny>,
    positions: Py<PyAny>,
    displacement: Py<PyAny>,
    velocity: Py<PyAny>,
    theta: Option<Py<PyAny>>,
    history: Py<PyDict>,
}

/// A read-only numpy array of `values` (moved, not copied) with `shape`.
fn array(py: Python<'_>, values: Vec<f64>, shape: &[usize]) -> PyResult<Py<PyAny>> {
    let a = PyArray1::from_vec(py, values).reshape(shape.to_vec())?;
    let flags = PyDict::new(py);
    flags.set_item("write", false)?;
    a.call_method("setflags", (), Some(&flags))?;
    Ok(a.into_any().unbind())
}

/// The values of an array made by [`array`], in order.
fn values(py: Python<'_>, a: &Py<PyAny>) -> PyResult<Vec<f64>> {
    Ok(a.bind(py).cast::<PyArrayDyn<f64>>()?.to_vec()?)
}

impl Run {
    fn new(
        py: Python<'_>,
        name: String,
        scene: AnyScene,
        mut recorded: Recorded,
    ) -> PyResult<Self> {
        let p = &mut recorded.profile;
        let (kept, n, k) = (p.times.len(), p.nodes(), p.components);
        let fields = if k == 1 {
            vec![kept, n]
        } else {
            vec![kept, n, k]
        };
        let positions = if k == 1 {
            array(py, p.x.clone(), &[n])?
        } else {
            let xy: Vec<f64> = p.x.iter().zip(&p.y).flat_map(|(x, y)| [*x, *y]).collect();
            array(py, xy, &[n, 2])?
        };
        let times = array(py, take(&mut p.times), &[kept])?;
        let displacement = array(py, take(&mut p.displacement), &fields)?;
        let velocity = array(py, take(&mut p.velocity), &fields)?;
        let theta = (p.has_theta)
            .then(|| array(py, take(&mut p.theta), &[kept, n]))
            .transpose()?;
        let history = PyDict::new(py);
        for (column, v) in recorded
            .history_columns
            .iter()
            .zip(take(&mut recorded.history))
        {
            let len = v.len();
            history.set_item(column, array(py, v, &[len])?)?;
        }
        Ok(Run {
            times,
            positions,
            displacement,
            velocity,
            theta,
            history: history.unbind(),
            name,
            scene,
            recorded,
        })
    }

    /// The run's outputs with the profile arrays read back from numpy's.
    fn with_profiles(&self, py: Python<'_>) -> PyResult<Recorded> {
        let mut recorded = self.recorded.clone();
        let p = &mut recorded.profile;
        p.times = values(py, &self.times)?;
        p.displacement = values(py, &self.displacement)?;
        p.velocity = values(py, &self.velocity)?;
        if let Some(theta) = &self.theta {
            p.theta = values(py, theta)?;
        }
        Ok(recorded)
    }
}

#[pymethods]
impl Run {
    /// The scene's name: the built-in name, the file's stem, or `"scene"` for TOML text or a
    /// dict.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// `"bar"` or `"plane"`.
    #[getter]
    fn body(&self) -> &str {
        &self.recorded.summary.body
    }

    /// A dict equal to `summary.json` (its clock fields `wall_time_s`, `ns_per_unknown_step`
    /// and `time_shares` measure this run).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = py.import("json")?;
        json.call_method1("loads", (self.recorded.summary_json(),))
    }

    /// `history.csv` as a dict of 1-D float64 arrays keyed by its column names, one value per
    /// step; a cell the file leaves empty (an energy term not measured, the extent of a
    /// contact set not in contact) is NaN.
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.history.bind(py).copy()
    }

    /// The kept steps' times (`t` of `displacement.csv`): t = 0, every `[output] every`-th
    /// step and the last.
    #[getter]
    fn times(&self, py: Python<'_>) -> Py<PyAny> {
        self.times.clone_ref(py)
    }

    /// The written nodes' positions: `x` (shape `(nodes,)`) on the bar, `(x, y)` (shape
    /// `(nodes, 2)`) on the plane.
    #[getter]
    fn positions(&self, py: Python<'_>) -> Py<PyAny> {
        self.positions.clone_ref(py)
    }

    /// The displacement at the kept steps and written nodes: shape `(kept steps, nodes)` on
    /// the bar, `(kept steps, nodes, 2)` on the plane (0 at clamped degrees of freedom).
    #[getter]
    fn displacement(&self, py: Python<'_>) -> Py<PyAny> {
        self.displacement.clone_ref(py)
    }

    /// The velocity `(u^n − u^{n−1})/Δt` at the kept steps, shaped as `displacement`.
    #[getter]
    fn velocity(&self, py: Python<'_>) -> Py<PyAny> {
        self.velocity.clone_ref(py)
    }

    /// The temperature `θ^{n−1/2}` at the kept steps and written nodes, shape `(kept steps,
    /// nodes)`, for a bar or a plane with `[heat]`; None otherwise.
    #[getter]
    fn theta(&self, py: Python<'_>) -> Option<Py<PyAny>> {
        self.theta.as_ref().map(|t| t.clone_ref(py))
    }

    /// Writes the command line's files of this run into the folder `path` (created if
    /// needed): `summary.json`, `history.csv` and `displacement.csv` from memory; a scene whose
    /// `[output] format` is `vtu` (or `npy`) is run again to write its files, as `viscobar run`
    /// does. Whole or not at all: a failure leaves earlier files untouched.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let csv =
            (self.recorded.summary.output).is_none_or(|s| s.format == scene::OutputFormat::Csv);
        let recorded = csv.then(|| self.with_profiles(py)).transpose()?;
        detached(py, || {
            if let Some(recorded) = recorded {
                return Ok(recorded.write_to_dir(&path)?);
            }
            match &self.scene {
                AnyScene::Bar(bar) => drop(run_to_dir(&self.name, bar, &path, false)?),
                AnyScene::Plane(plane) => drop(run_plane_to_dir(&self.name, plane, &path, false)?),
            }
            Ok(())
        })?;
        Ok(())
    }

    fn __repr__(&self) -> String {
        let s = &self.recorded.summary;
        format!(
            "<viscobar.Run {:?}: {} {} steps, {} kept, {} unknowns, solver {}>",
            self.name,
            s.body,
            s.steps,
            s.output.map_or(0, |o| o.kept_steps),
            s.unknowns,
            s.solver
        )
    }
}

/// The Python module `viscobar._viscobar`.
#[pymodule]
fn _viscobar(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_function(wrap_pyfunction!(scenes, m)?)?;
    m.add_function(wrap_pyfunction!(show, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_test, m)?)?;
    m.add_function(wrap_pyfunction!(_library_run_seconds, m)?)?;
    m.add_class::<Run>()?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    m.add("__version__", PyString::new(py, env!("CARGO_PKG_VERSION")))?;
    Ok(())
}
