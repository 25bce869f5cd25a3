//! The scenes handed to Python: a scene file's or the built-in bar's (`Kind`), their
//! construction from TOML, a dict (`tables`), the bar's JSON and overrides with errors
//! in Python terms (`_Scene`).

use super::*;

/// A built model, with its report when it comes from a scene file.
pub(crate) type Built = (
    signorini::scene::Model,
    Option<signorini::scene::file::ModelReport>,
);

/// A scene file's scene, or the built-in impacting bar (its own parameter set).
#[derive(Clone)]
pub(crate) enum Kind {
    File(Box<FileScene>),
    Bar(Box<BarScene>),
}

impl Kind {
    pub(crate) fn steps(&self) -> usize {
        match self {
            Kind::File(s) => s.steps(),
            Kind::Bar(b) => b.steps(),
        }
    }

    /// The model (mesh, assembly, contacts), as a run builds it, with a scene file's
    /// report.
    pub(crate) fn build(&self) -> Result<Built, Error> {
        match self {
            Kind::File(s) => s.build().map(|(m, r)| (m, Some(r))),
            Kind::Bar(b) => Ok((b.build()?, None)),
        }
    }

    /// Opens the run (a [`Session`]) into `out`, from `built` where given.
    pub(crate) fn session(
        &self,
        built: Option<Built>,
        out: Output,
        progress: &mut dyn Progress,
    ) -> Result<Session, Error> {
        match self {
            Kind::File(s) => {
                let built = built.map(|(m, r)| (m, r.expect("a scene file's model has a report")));
                Session::scene(s, built, Some(out), progress, None)
            }
            Kind::Bar(b) => Session::bar(b, built.map(|b| b.0), Some(out), progress, None),
        }
    }

    /// The scene's output options.
    pub(crate) fn output(&self) -> OutputOptions {
        match self {
            Kind::File(s) => s.output.clone(),
            Kind::Bar(_) => OutputOptions::default(),
        }
    }

    /// The bodies' names, in the order of the model's bodies.
    pub(crate) fn body_names(&self) -> Vec<String> {
        match self {
            Kind::File(s) => s.bodies.iter().map(|b| b.name.clone()).collect(),
            Kind::Bar(_) => vec!["bar".to_string()],
        }
    }
}

/// A validated scene (`signorini.Scene` wraps it).
#[pyclass(module = "signorini._signorini", name = "_Scene", frozen)]
pub(crate) struct PyScene {
    pub(crate) kind: Kind,
}

fn file_scene(s: FileScene) -> PyScene {
    PyScene {
        kind: Kind::File(Box::new(s)),
    }
}

#[pymethods]
impl PyScene {
    /// A scene file with `KEY=VALUE` overrides (`signorini run FILE --set …`).
    #[staticmethod]
    fn from_file(path: PathBuf, set: Vec<String>) -> PyResult<Self> {
        FileScene::from_file_with(&path, &set)
            .map(file_scene)
            .map_err(py_err)
    }

    /// Scene TOML text; relative mesh paths start from `base_dir` (default: the
    /// working directory).
    #[staticmethod]
    #[pyo3(signature = (text, set, base_dir=None))]
    fn from_text(text: &str, set: Vec<String>, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let mut s = FileScene::from_text_with(text, &set).map_err(py_err)?;
        if let Some(d) = base_dir {
            s.base_dir = d;
        }
        Ok(file_scene(s))
    }

    /// A scene given as the dict of its tables, read with no text (`tables`): the
    /// arrays of a mesh given as arrays and the per-node fields copied once, after
    /// their shapes and the memory limit are checked; errors name the key path.
    #[staticmethod]
    #[pyo3(signature = (tables, set, base_dir=None))]
    fn from_dict(
        tables: &Bound<'_, PyAny>,
        set: Vec<String>,
        base_dir: Option<PathBuf>,
    ) -> PyResult<Self> {
        let mut s = super::tables::scene_from_dict(tables, &set)?;
        if let Some(d) = base_dir {
            s.base_dir = d;
        }
        Ok(file_scene(s))
    }

    /// The built-in impacting bar from its parameters as JSON (the reference bar for
    /// `{}`); unknown names are refused with the name.
    #[staticmethod]
    fn bar(json: &str) -> PyResult<Self> {
        let mut de = serde_json::Deserializer::from_str(json);
        let b: BarScene = serde_path_to_error_free(&mut de)?;
        b.validate().map_err(py_err)?;
        Ok(PyScene {
            kind: Kind::Bar(Box::new(b)),
        })
    }

    /// One of the paper's academic examples (bouncing-ball, oscillator, rocking-block,
    /// slider-crank).
    #[staticmethod]
    fn example(name: &str) -> PyResult<Self> {
        signorini::scene::builtin_scene(name)
            .map(file_scene)
            .map_err(py_err)
    }

    /// This scene with overrides (file scenes; the bar takes new parameters instead).
    fn with_overrides(&self, set: Vec<String>) -> PyResult<Self> {
        match &self.kind {
            Kind::File(s) => s.with_overrides(&set).map(file_scene).map_err(py_err),
            Kind::Bar(_) => Err(BadInput::new_err(
                "the built-in bar takes parameters, not scene keys",
            )),
        }
    }

    /// Whether this is the built-in bar.
    fn is_bar(&self) -> bool {
        matches!(self.kind, Kind::Bar(_))
    }

    /// The scene as JSON (file scenes: the TOML tables; the bar: its parameters);
    /// absent optional keys are left out, as in a scene file.
    fn to_json(&self) -> String {
        let mut v = match &self.kind {
            Kind::File(s) => serde_json::to_value(s.as_ref()),
            Kind::Bar(b) => serde_json::to_value(b),
        }
        .expect("scenes serialize");
        strip_nulls(&mut v);
        v.to_string()
    }

    /// The directory relative mesh paths start from (file scenes; None for the bar).
    fn base_dir(&self) -> Option<PathBuf> {
        match &self.kind {
            Kind::File(s) => Some(s.base_dir.clone()),
            Kind::Bar(_) => None,
        }
    }

    /// The scene as TOML text.
    fn to_toml(&self) -> PyResult<String> {
        match &self.kind {
            Kind::File(s) => toml::to_string(s.as_ref()),
            Kind::Bar(b) => toml::to_string(b),
        }
        .map_err(|e| PyRuntimeError::new_err(format!("the scene does not serialize: {e}")))
    }

    /// Steps of a run.
    fn steps(&self) -> usize {
        self.kind.steps()
    }

    /// What `signorini check` reports, as JSON.
    fn check(&self) -> PyResult<String> {
        let c = match &self.kind {
            Kind::File(s) => s.check(),
            Kind::Bar(b) => b.check(),
        }
        .map_err(py_err)?;
        Ok(serde_json::to_string(&c).expect("the report serializes"))
    }
}

/// Drops `null` values (TOML has none: an absent key means the default; Python's
/// `None` reads the same way).
fn strip_nulls(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|_, x| !x.is_null());
            m.values_mut().for_each(strip_nulls);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_nulls),
        _ => {}
    }
}

/// The bar's parameters from JSON, an error naming the parameter by its key path in
/// Python's spelling (`scheme.kind`, `dt`) instead of a line and column of the JSON text.
fn serde_path_to_error_free<T: serde::de::DeserializeOwned>(
    de: &mut serde_json::Deserializer<serde_json::de::StrRead<'_>>,
) -> PyResult<T> {
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner().to_string();
        // serde_json's message ends with the position in the JSON text, which the
        // caller never wrote
        let msg = inner
            .rsplit_once(" at line ")
            .map_or(inner.as_str(), |(m, _)| m)
            .replace("expected f64", "expected a number")
            .replace("expected usize", "expected a whole number ≥ 0");
        if path == "." {
            BadInput::new_err(format!("Scene.bar: {msg}"))
        } else {
            BadInput::new_err(format!("invalid value for `{path}`: {msg}"))
        }
    })
}
