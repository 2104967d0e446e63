//! Python's arguments as the command line's: a scene given by name, path, TOML text or dict,
//! `set` as `--set KEY=VALUE` assignments, `solver` as `--solver`.

use crate::SceneError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use viscobar::scene::{self, AnyScene};

/// The name a scene given as TOML text or as a dict runs under (`summary.json`'s `scene`).
pub const INLINE_NAME: &str = "scene";

/// A scene as the library reads it: its TOML text or its name or path, and the
/// `key=value` assignments to apply.
pub struct Source {
    scene: Scene,
    overrides: Vec<String>,
}

enum Scene {
    Text(String),
    NameOrPath(String),
}

impl Source {
    /// The scene `scene` with the assignments of `set` and `solver`, read from Python (the
    /// library reads it in [`Source::load`]).
    pub fn new(
        scene: &Bound<'_, PyAny>,
        set: Option<&Bound<'_, PyDict>>,
        solver: Option<&str>,
    ) -> PyResult<Self> {
        let mut overrides = Vec::new();
        for (key, value) in set.into_iter().flat_map(|d| d.iter()) {
            let key: String = key
                .extract()
                .map_err(|_| SceneError::new_err(format!("set: a key is not a str: {key}")))?;
            let text = if let Ok(s) = value.cast::<PyString>() {
                s.to_cow()?.into_owned()
            } else {
                toml_value(&value, &key)?.to_string()
            };
            overrides.push(format!("{key}={text}"));
        }
        // After `set`, as the command line puts `--solver` after the `--set`s.
        if let Some(s) = solver {
            overrides.push(format!("solver.method=\"{s}\""));
        }
        if let Ok(table) = scene.cast::<PyDict>() {
            let mut t = toml::Table::new();
            for (key, value) in table.iter() {
                let key: String = key.extract().map_err(|_| {
                    SceneError::new_err(format!("scene: a key is not a str: {key}"))
                })?;
                let v = toml_value(&value, &key)?;
                t.insert(key, v);
            }
            let text = toml::to_string(&t).map_err(|e| SceneError::new_err(e.to_string()))?;
            let scene = Scene::Text(text);
            return Ok(Source { scene, overrides });
        }
        let text: String = if let Ok(s) = scene.cast::<PyString>() {
            s.to_cow()?.into_owned()
        } else {
            // A path-like object.
            let os = scene.py().import("os")?;
            let path = os.call_method1("fspath", (scene,)).map_err(|_| {
                SceneError::new_err(format!(
                    "scene: a built-in name, a path, TOML text or a dict, not {}",
                    scene
                        .get_type()
                        .name()
                        .map_or("this".into(), |n| n.to_string())
                ))
            })?;
            path.extract()?
        };
        let scene = if is_toml_text(&text) {
            Scene::Text(text)
        } else {
            Scene::NameOrPath(text)
        };
        Ok(Source { scene, overrides })
    }

    /// The scene read, validated and overridden as the command line does, and its name.
    pub fn load(&self) -> Result<(String, AnyScene), scene::SceneError> {
        match &self.scene {
            Scene::Text(text) => Ok((
                INLINE_NAME.into(),
                scene::plane::any_from_toml(text, &self.overrides)?,
            )),
            Scene::NameOrPath(name) => scene::load_any(name, &self.overrides),
        }
    }
}

/// TOML text rather than a name or a path: a line break, or an `=` with no file of that name.
fn is_toml_text(text: &str) -> bool {
    text.contains('\n') || (text.contains('=') && !std::path::Path::new(text).exists())
}

/// The TOML value of a Python value (bool, int, float, str, dict, list or tuple) at `key`.
fn toml_value(value: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    Ok(if let Ok(b) = value.cast::<PyBool>() {
        toml::Value::Boolean(b.is_true())
    } else if value.is_instance_of::<PyInt>() {
        toml::Value::Integer(value.extract()?)
    } else if value.is_instance_of::<PyFloat>() {
        toml::Value::Float(value.extract()?)
    } else if let Ok(s) = value.cast::<PyString>() {
        toml::Value::String(s.to_cow()?.into_owned())
    } else if let Ok(d) = value.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, v) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| SceneError::new_err(format!("`{key}`: a key is not a str: {k}")))?;
            let inner = toml_value(&v, &format!("{key}.{k}"))?;
            t.insert(k, inner);
        }
        toml::Value::Table(t)
    } else if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items = (value.try_iter()?)
            .map(|item| toml_value(&item?, key))
            .collect::<PyResult<Vec<_>>>()?;
        toml::Value::Array(items)
    } else if let Ok(i) = value.extract::<i64>() {
        // numpy's integers.
        toml::Value::Integer(i)
    } else if let Ok(x) = value.extract::<f64>() {
        toml::Value::Float(x)
    } else {
        let kind = value
            .get_type()
            .name()
            .map_or("?".into(), |n| n.to_string());
        return Err(SceneError::new_err(format!(
            "`{key}` = {value}: a value of type {kind} has no TOML form (bool, int, float, str, \
             dict, list)"
        )));
    })
}
