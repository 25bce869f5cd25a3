//! Reading a scene: TOML text or file to [`Scene`], with `--set KEY=VALUE` overrides
//! applied to the TOML table before it is typed.

use super::*;

impl Scene {
    /// Reads and validates a scene file; errors name the file and the key path (or the
    /// line and column of a TOML syntax error).
    pub fn from_file(path: &Path) -> Result<Scene, Error> {
        let text = crate::limits::read_text(path, "scene", crate::limits::MAX_SCENE_BYTES)?;
        let mut scene = Self::from_toml(&text).map_err(|e| e.in_file(path))?;
        scene.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        scene.file = Some(path.to_path_buf());
        Ok(scene)
    }

    /// [`Scene::from_file`] with `KEY=VALUE` overrides applied to the file's TOML before
    /// it is read as a scene (`signorini run --set`): `KEY` is a dotted path with array
    /// indices (`scheme.newton.modified`, `bodies[0].material.model`), tables on the path
    /// are created, and `VALUE` is a TOML value (`true`, `1e-5`, `"svk"`). The scene is
    /// then validated as usual, so a misspelt key is refused with its path.
    pub fn from_file_with(path: &Path, overrides: &[String]) -> Result<Scene, Error> {
        if overrides.is_empty() {
            return Self::from_file(path);
        }
        let text = crate::limits::read_text(path, "scene", crate::limits::MAX_SCENE_BYTES)?;
        let mut scene = Self::from_text_with(&text, overrides).map_err(|e| e.in_file(path))?;
        scene.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        scene.file = Some(path.to_path_buf());
        Ok(scene)
    }

    /// [`Scene::from_toml`] with the `KEY=VALUE` overrides of [`Scene::from_file_with`]
    /// (relative mesh paths then start from the working directory).
    pub fn from_text_with(text: &str, overrides: &[String]) -> Result<Scene, Error> {
        // syntax errors are located in the text itself
        let mut table: toml::Table = match toml::from_str(text) {
            Ok(t) if !overrides.is_empty() => t,
            _ => return Self::from_toml(text),
        };
        for o in overrides {
            apply_override(&mut table, o)?;
        }
        let text = toml::to_string(&table)
            .map_err(|e| Error::invalid("--set", "(scene)", &format!("does not serialize: {e}")))?;
        Self::from_toml(&text)
    }

    /// This scene with the `KEY=VALUE` overrides of [`Scene::from_file_with`] applied,
    /// keeping its file and base directory (the Python package's keyword arguments).
    ///
    /// No text: the scene's tables are TOML values, and the arrays of a mesh given as
    /// arrays and the per-node field rows are set aside and put back as they are, unless
    /// an override names them (issue 48: `simulation(t_end=…)` on a 10⁶-point mesh went
    /// through TOML text, 5.8 s and 1.6 GB).
    pub fn with_overrides(&self, overrides: &[String]) -> Result<Scene, Error> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let keys: Vec<&str> = overrides
            .iter()
            .map(|o| o.split_once('=').map_or(o.as_str(), |(k, _)| k).trim())
            .collect();
        // `key` names `slot` or a table around it or a key inside it
        let named = |slot: &str| {
            let under = |a: &str, b: &str| {
                a == b || a.starts_with(&format!("{b}.")) || a.starts_with(&format!("{b}["))
            };
            keys.iter().any(|k| under(k, slot) || under(slot, k))
        };
        let mut small = self.clone();
        let mut aside = Vec::new();
        for (i, b) in small.bodies.iter_mut().enumerate() {
            let mut mesh = None;
            if let MeshSpec::Arrays {
                points,
                cells,
                node_sets,
            } = &mut b.mesh
                && !["points", "cells", "node_sets"]
                    .iter()
                    .any(|k| named(&format!("bodies[{i}].mesh.{k}")))
            {
                mesh = Some((
                    std::mem::take(points),
                    std::mem::take(cells),
                    std::mem::take(node_sets),
                ));
            }
            let mut fields = [None, None];
            for (slot, (key, field)) in fields.iter_mut().zip([
                ("initial_velocity", &mut b.initial_velocity),
                ("initial_displacement", &mut b.initial_displacement),
            ]) {
                if let Some(NodalField::Rows(rows)) = field
                    && !named(&format!("bodies[{i}].{key}"))
                {
                    *slot = Some(std::mem::take(rows));
                }
            }
            aside.push((mesh, fields));
        }
        let table = toml::Table::try_from(&small)
            .map_err(|e| Error::invalid("--set", "(scene)", &format!("does not serialize: {e}")))?;
        let mut scene = Self::from_table(table, overrides)?;
        if !aside
            .iter()
            .all(|(m, f)| m.is_none() && f.iter().all(Option::is_none))
        {
            // the bodies are those set aside: an override of `bodies` itself names
            // every slot, so nothing was
            for (b, (mesh, fields)) in scene.bodies.iter_mut().zip(aside) {
                if let (
                    Some(arrays),
                    MeshSpec::Arrays {
                        points,
                        cells,
                        node_sets,
                    },
                ) = (mesh, &mut b.mesh)
                {
                    (*points, *cells, *node_sets) = arrays;
                }
                for (rows, field) in fields
                    .into_iter()
                    .zip([&mut b.initial_velocity, &mut b.initial_displacement])
                {
                    if let (Some(rows), Some(NodalField::Rows(r))) = (rows, field) {
                        *r = rows;
                    }
                }
            }
            scene.validate()?;
        }
        scene.base_dir = self.base_dir.clone();
        scene.file = self.file.clone();
        Ok(scene)
    }

    /// A scene from its tables as TOML values built in code (the Python package builds
    /// them from a dict, with no text), with the `KEY=VALUE` overrides of
    /// [`Scene::from_file_with`]; validated as a scene file is, errors naming the key
    /// path (`bodies[0].material.young`). Equal to the scene of the same tables written
    /// as TOML text and read by [`Scene::from_toml`]. Relative mesh paths start from the
    /// working directory (set [`Scene::base_dir`] for another).
    ///
    /// ```
    /// use signorini::scene::file::Scene;
    /// let text = "[time]\ndt = 1e-6\nt_end = 1e-3\n[example]\nkind = \"bouncing-ball\"\n";
    /// let table: toml::Table = toml::from_str(text).unwrap();
    /// let scene = Scene::from_table(table, &["time.dt=2e-6".to_string()]).unwrap();
    /// assert_eq!(scene.steps(), 500);
    /// ```
    pub fn from_table(mut table: toml::Table, overrides: &[String]) -> Result<Scene, Error> {
        for o in overrides {
            apply_override(&mut table, o)?;
        }
        let scene: Scene = serde_path_to_error::deserialize(table).map_err(|e| {
            let path = e.path().to_string();
            let field = if path == "." || path.is_empty() {
                "scene".to_string()
            } else {
                path
            };
            Error::invalid(&field, "(key)", first_line(e.inner().message()))
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Parses and validates scene text.
    pub fn from_toml(text: &str) -> Result<Scene, Error> {
        let at = |span: Option<std::ops::Range<usize>>| match span {
            Some(r) => {
                let before = &text[..r.start.min(text.len())];
                let line = 1 + before.matches('\n').count();
                let col = 1 + before.len() - before.rfind('\n').map_or(0, |i| i + 1);
                format!("line {line}, column {col}")
            }
            None => "scene".to_string(),
        };
        let de = toml::Deserializer::parse(text)
            .map_err(|e| Error::invalid(&at(e.span()), "(TOML syntax)", first_line(e.message())))?;
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let field = if path == "." || path.is_empty() {
                at(inner.span())
            } else {
                path
            };
            let message = first_line(inner.message());
            match message
                .strip_prefix(KEY_MARK)
                .map(|m| m.splitn(3, KEY_MARK).collect::<Vec<_>>())
            {
                // an error below the path serde knows ([`at_key`])
                Some(parts) if parts.len() == 3 => {
                    let sub = parts[0];
                    let sub = if sub.is_empty() || sub.starts_with(['.', '[']) {
                        sub.to_string()
                    } else {
                        format!(".{sub}")
                    };
                    Error::invalid(&format!("{field}{sub}"), parts[1], parts[2])
                }
                _ => Error::invalid(&field, "(key)", message),
            }
        })?;
        scene.validate()?;
        Ok(scene)
    }
}

/// Sets `KEY=VALUE` in a scene's TOML table ([`Scene::from_file_with`]).
pub(super) fn apply_override(table: &mut toml::Table, o: &str) -> Result<(), Error> {
    let bad = |why: &str| Error::invalid("--set", o, why);
    let (key, value) = o
        .split_once('=')
        .ok_or_else(|| bad("expected KEY=VALUE, e.g. scheme.newton.modified=true"))?;
    // exactly one value: `2e-6\n[evil]\nx = 1` parses as a document with more in it,
    // which was dropped (issue 34)
    let value: toml::Value = toml::from_str::<toml::Table>(&format!("v = {}", value.trim()))
        .ok()
        .filter(|t| t.len() == 1)
        .and_then(|mut t| t.remove("v"))
        .ok_or_else(|| {
            bad("VALUE is not one TOML value (quote strings: model=\"svk\"; no line breaks)")
        })?;
    // segments: names, each with optional [index]
    let mut path: Vec<(&str, Option<usize>)> = Vec::new();
    for seg in key.trim().split('.') {
        let (name, index) = match seg.split_once('[') {
            Some((n, rest)) => {
                let i = rest
                    .strip_suffix(']')
                    .and_then(|i| i.parse::<usize>().ok())
                    .ok_or_else(|| bad("an index is written name[0]"))?;
                (n, Some(i))
            }
            None => (seg, None),
        };
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(bad(
                "KEY is a dotted path of names, e.g. bodies[0].material.model",
            ));
        }
        path.push((name, index));
    }
    let (last, parents) = path.split_last().expect("at least one segment");
    let mut cur = table;
    for &(name, index) in parents {
        let entry = cur
            .entry(name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let next = match index {
            None => entry,
            Some(i) => {
                let len = entry.as_array().map_or(0, |a| a.len());
                entry
                    .as_array_mut()
                    .and_then(|a| a.get_mut(i))
                    .ok_or_else(|| bad(&format!("`{name}` has {len} entries; no [{i}]")))?
            }
        };
        cur = next
            .as_table_mut()
            .ok_or_else(|| bad(&format!("`{name}` is not a table")))?;
    }
    match last.1 {
        None => {
            cur.insert(last.0.to_string(), value);
        }
        Some(i) => {
            let arr = cur
                .get_mut(last.0)
                .and_then(|v| v.as_array_mut())
                .ok_or_else(|| bad(&format!("`{}` is not an array", last.0)))?;
            let len = arr.len();
            *arr.get_mut(i)
                .ok_or_else(|| bad(&format!("`{}` has {len} entries; no [{i}]", last.0)))? = value;
        }
    }
    Ok(())
}

/// The first line of a parser's message (toml's messages carry a source excerpt after it).
pub(super) fn first_line(m: &str) -> &str {
    m.lines().next().unwrap_or(m).trim()
}
