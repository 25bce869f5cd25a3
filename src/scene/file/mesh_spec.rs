//! A body's mesh as a scene names it: generated or read from a file, its node sets and the
//! facets of a contact target.

use super::*;
use crate::model::element::MAX_NODES;

impl BodySpec {
    /// The displacement components of a node of this body: 1 for a rod, else its
    /// formulation's (2 or 3).
    pub fn dim(&self) -> usize {
        match self.mesh {
            MeshSpec::Rod { .. } => 1,
            _ => self.formulation.dim(),
        }
    }

    pub(super) fn mesh(&self, base: &Path) -> Result<Mesh, Error> {
        match &self.mesh {
            MeshSpec::File { path } => {
                let m = crate::io::mesh::read_mesh(&base.join(path))?;
                // measured against the memory limit before it is assembled (issue 34: a
                // 40³ hex8 file under a 96 MiB limit was refused only after its assembly,
                // at a peak of 1.1 GiB)
                let per_cell = m.cells.iter().map(|(_, c)| c.len()).max().unwrap_or(1);
                crate::limits::mesh_memory(
                    m.points.len() as u64,
                    m.cells.len() as u64,
                    per_cell as u64,
                    self.dim() as u64,
                )
                .check("mesh.path", path.display())?;
                Ok(m)
            }
            MeshSpec::Box {
                cell,
                cells,
                size,
                origin,
            } => {
                generator_checks("box", *cell, cells, size, origin)?;
                let mut m = box_mesh(*cell, *cells, *size);
                for p in &mut m.points {
                    for i in 0..3 {
                        p[i] += origin[i];
                    }
                }
                Ok(m)
            }
            MeshSpec::Rectangle {
                cell,
                cells,
                size,
                origin,
            } => {
                generator_checks("rectangle", *cell, cells, size, origin)?;
                let mut m = rectangle_mesh(*cell, *cells, *size);
                for p in &mut m.points {
                    p[0] += origin[0];
                    p[1] += origin[1];
                }
                Ok(m)
            }
            MeshSpec::Arrays {
                points,
                cells,
                node_sets,
            } => arrays_mesh(points, cells, node_sets, self.dim()),
            MeshSpec::Rod {
                elements,
                length,
                origin,
                ..
            } => {
                crate::error::require_finite("mesh.origin", *origin)?;
                if *elements == 0 {
                    return Err(Error::invalid("mesh.elements", 0, "must be at least 1"));
                }
                require_positive("mesh.length", *length)?;
                let n = *elements as u64;
                crate::limits::mesh_memory(n + 1, n, 2, 1).check("mesh.elements", n)?;
                let mut m = Mesh::default();
                let n = *elements;
                for i in 0..=n {
                    m.points
                        .push([origin + *length * i as f64 / n.max(1) as f64, 0.0, 0.0]);
                }
                m.node_sets =
                    BTreeMap::from([("x0".to_string(), vec![0]), ("x1".to_string(), vec![n])]);
                Ok(m)
            }
        }
    }
}

/// The mesh of `generator = "arrays"` for a body of dimension `dim` (2 or 3), every
/// entry checked: finite coordinates of `dim` (or 3, z = 0 in 2-D) values, known cell
/// kinds with their node counts, indices within `points`, every point in a cell (a point
/// no cell holds has no mass), node sets within `points`; the size against the memory
/// limit before anything is built. Cell shapes (inverted, degenerate) are checked with
/// the formulation afterwards, as for files.
fn arrays_mesh(
    points: &Rows<f64>,
    cells: &BTreeMap<String, Rows<usize>>,
    node_sets: &BTreeMap<String, Vec<usize>>,
    dim: usize,
) -> Result<Mesh, Error> {
    let np = points.len();
    let nc: usize = cells.values().map(Rows::len).sum();
    let shapes: Vec<(usize, usize)> = cells
        .values()
        .map(|c| (c.len(), c.width().unwrap_or(8)))
        .collect();
    arrays_memory(np, points.width().unwrap_or(3), &shapes, dim)
        .check("mesh.points", format!("{np} points and {nc} cells"))?;
    if np == 0 || nc == 0 {
        return Err(Error::invalid(
            if np == 0 { "mesh.points" } else { "mesh.cells" },
            "[]",
            "needs at least one point and one cell",
        ));
    }
    let mut mesh = Mesh {
        points: Vec::with_capacity(np),
        ..Mesh::default()
    };
    for (i, p) in points.iter().enumerate() {
        let key = || format!("mesh.points[{i}]");
        if !(p.len() == dim || p.len() == 3) {
            return Err(Error::invalid(
                &key(),
                format!("{p:?}"),
                &format!(
                    "needs {dim} coordinates (m){}",
                    if dim == 2 { " or 3 with z = 0" } else { "" }
                ),
            ));
        }
        if let Some(x) = p.iter().find(|x| !x.is_finite()) {
            return Err(Error::invalid(&key(), x, "must be finite"));
        }
        if dim == 2 && p.len() == 3 && p[2] != 0.0 {
            return Err(Error::invalid(
                &key(),
                format!("{p:?}"),
                "a plane body lies in z = 0",
            ));
        }
        mesh.points
            .push([p[0], p[1], p.get(2).copied().unwrap_or(0.0)]);
    }
    let mut used = vec![false; np];
    // each cell by its sorted nodes → where it was first listed: a cell listed twice
    // would add its mass and stiffness twice (a hex8 cube listed twice weighed 1.125 kg
    // for 1 kg)
    // (the key: the sorted nodes, padded; at most MAX_NODES a cell — no allocation per cell)
    let mut seen: std::collections::HashMap<[usize; MAX_NODES], (&str, usize)> =
        std::collections::HashMap::with_capacity(nc.min(1 << 24));
    for (name, list) in cells {
        let kind: CellKind = serde_json::from_value(serde_json::Value::String(name.clone()))
            .map_err(|_| {
                Error::invalid(
                    "mesh.cells",
                    name,
                    &format!("is not a cell kind: {}", CellKind::names(None)),
                )
            })?;
        mesh.cells.reserve(list.len());
        for (c, nodes) in list.iter().enumerate() {
            let key = || format!("mesh.cells.{name}[{c}]");
            if nodes.len() != kind.nodes() {
                return Err(Error::invalid(
                    &key(),
                    format!("{nodes:?}"),
                    &format!("a {name} cell has {} nodes", kind.nodes()),
                ));
            }
            if let Some(&v) = nodes.iter().find(|&&v| v >= np) {
                return Err(Error::invalid(
                    &key(),
                    v,
                    &format!("is not a point index: mesh.points has {np} points (0-based)"),
                ));
            }
            nodes.iter().for_each(|&v| used[v] = true);
            let mut sorted = [usize::MAX; MAX_NODES];
            sorted[..nodes.len()].copy_from_slice(nodes);
            sorted.sort_unstable();
            if let Some((first, fc)) = seen.insert(sorted, (name.as_str(), c)) {
                return Err(Error::invalid(
                    &key(),
                    format!("{nodes:?}"),
                    &format!(
                        "has the nodes of mesh.cells.{first}[{fc}]: a cell listed twice would \
                         count its mass and stiffness twice (list each cell once)"
                    ),
                ));
            }
            mesh.cells.push((kind, nodes.to_vec()));
        }
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(Error::invalid(
            &format!("mesh.points[{i}]"),
            format!("{:?}", points.row(i)),
            "is in no cell: such a point has no mass or stiffness (drop it)",
        ));
    }
    for (name, set) in node_sets {
        if name == "all" {
            return Err(Error::invalid(
                "mesh.node_sets.all",
                format!("{} node(s)", set.len()),
                "`all` is a reserved name: it always means every node of the mesh; \
                 give your set another name",
            ));
        }
        if let Some(&v) = set.iter().find(|&&v| v >= np) {
            return Err(Error::invalid(
                &format!("mesh.node_sets.{name}"),
                v,
                &format!("is not a point index: mesh.points has {np} points (0-based)"),
            ));
        }
        let mut set = set.clone();
        set.sort_unstable();
        set.dedup();
        mesh.node_sets.insert(name.clone(), set);
    }
    Ok(mesh)
}

/// The nodes of the set `name` of `mesh`: a named set, `boundary` (computed from the
/// cells when the mesh has no set of that name) or `all`.
pub(super) fn node_set(mesh: &crate::model::solid::Mesh, name: &str) -> Result<Vec<usize>, Error> {
    // an empty set fixes, drives, loads or probes nothing (issue 34: `fixed` and
    // `prescribed` accepted one silently)
    let set = node_set_any(mesh, name)?;
    if set.is_empty() {
        return Err(Error::invalid(
            "nodes",
            name,
            "the node set is empty: it names no node of the mesh",
        ));
    }
    Ok(set)
}

/// The nodes of set `name` of `mesh` (`all`, `boundary` computed when the mesh has no
/// set of that name), possibly none.
pub(super) fn node_set_any(
    mesh: &crate::model::solid::Mesh,
    name: &str,
) -> Result<Vec<usize>, Error> {
    if name == "all" {
        Ok((0..mesh.points.len()).collect())
    } else if name == "boundary" && !mesh.node_sets.contains_key("boundary") {
        Ok(mesh.boundary_nodes())
    } else {
        mesh.node_sets.get(name).cloned().ok_or_else(|| {
            Error::invalid(
                "nodes",
                name,
                &format!(
                    "no such node set; the mesh has {} (and `boundary`, `all`)",
                    {
                        let mut names: Vec<_> =
                            mesh.node_sets.keys().map(|k| format!("`{k}`")).collect();
                        names.sort();
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join(", ")
                        }
                    }
                ),
            )
        })
    }
}

/// The master surface of a contact between bodies: the boundary facets of `target`'s
/// surface set on `mesh` (a rod's ends in the set, each with its outward direction),
/// and how many facets on the axis were left out.
///
/// An axisymmetric body's mesh is its half section `x = r ≥ 0`: its edges on the axis
/// `r = 0` bound the section, not the revolved solid, and are never contact facets
/// (issue 33: a `surface = "boundary"` that kept them paired a pole with an axis edge
/// at gap 0 while 2 µm apart). An edge whose nodes both lie within 1e-9 of the
/// section's width from the axis is left out; `check` reports the count.
pub(super) fn target_facets(
    mesh: &Mesh,
    body: &BodySpec,
    t: &TargetSpec,
    rule: super::ContactRule,
) -> Result<(Vec<Vec<usize>>, usize), Error> {
    let set = node_set(mesh, &t.surface).map_err(|e| prefix("surface", e))?;
    let mut facets = if let MeshSpec::Rod { .. } = body.mesh {
        // a rod's facets are its end nodes; the direction is recovered by `bodies::build`
        // from the neighbouring node
        let last = mesh.points.len() - 1;
        set.iter()
            .filter(|&&v| v == 0 || v == last)
            .map(|&v| vec![v])
            .collect()
    } else {
        let facets = mesh.boundary_facets(&set);
        // a quadratic facet is a curve or a curved face: node-to-surface facets are
        // straight segments, triangles and quadrilaterals; mortar rows take curves
        if let Some(f) = facets.iter().find(|f| {
            rule != super::ContactRule::Surface
                && crate::model::element::facet_corners(body.dim(), f.len()) != Some(f.len())
        }) {
            return Err(Error::invalid(
                "surface",
                &t.surface,
                &format!(
                    "has a facet of {} nodes (a quadratic cell's): a body's contact target \
                     takes linear cells (tri3, quad4, tet4, hex8) with rule = \"nodes\"; \
                     rule = \"surface\" takes 2-D quadratic edges, and contacts of its nodes \
                     against an obstacle take any cell",
                    f.len()
                ),
            ));
        }
        facets
    };
    let mut on_axis = 0;
    if matches!(body.formulation, Formulation::Axisymmetric) {
        let width = mesh.points.iter().fold(0.0f64, |w, p| w.max(p[0].abs()));
        let tol = 1e-9 * width;
        let before = facets.len();
        facets.retain(|f| !f.iter().all(|&v| mesh.points[v][0].abs() <= tol));
        on_axis = before - facets.len();
    }
    if facets.is_empty() {
        return Err(Error::invalid(
            "surface",
            &t.surface,
            &format!(
                "holds no boundary facet of body \"{}\" (a facet counts when all its nodes \
                 are in the set{})",
                t.body,
                if on_axis > 0 {
                    format!(
                        "; its {on_axis} facet(s) on the axis r = 0 are not surfaces of the revolved solid"
                    )
                } else {
                    String::new()
                }
            ),
        ));
    }
    Ok((facets, on_axis))
}

/// `mesh.cells` of an arrays mesh, read with the key path and the value of an entry
/// that is not a point index (the mesh's tagged table hides the path from serde: a
/// negative or fractional index was refused as "`bodies[0].mesh`: expected usize").
pub(super) fn cell_lists<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<BTreeMap<String, super::Rows<usize>>, D::Error> {
    let lists = d.deserialize_any(Table {
        at: ".cells",
        lists: true,
    })?;
    Ok(lists
        .into_iter()
        .map(|(k, v)| (k, super::Rows::from_rows(v)))
        .collect())
}

/// `mesh.node_sets` of an arrays mesh, read as [`cell_lists`] is.
pub(super) fn index_sets<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<BTreeMap<String, Vec<usize>>, D::Error> {
    let sets = d.deserialize_any(Table {
        at: ".node_sets",
        lists: false,
    })?;
    Ok(sets
        .into_iter()
        .map(|(k, mut v)| (k, v.pop().unwrap_or_default()))
        .collect())
}

/// A table of index lists (`lists`: of lists of lists, the cells by kind; else of
/// lists, the node sets, each returned as a one-element vector).
struct Table {
    at: &'static str,
    lists: bool,
}

impl<'de> serde::de::Visitor<'de> for Table {
    type Value = BTreeMap<String, Vec<Vec<usize>>>;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "a table of point-index lists")
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut out = BTreeMap::new();
        while let Some(name) = map.next_key::<String>()? {
            let at = format!("{}.{name}", self.at);
            let value = if self.lists {
                map.next_value_seed(Lists { at: &at })?
            } else {
                vec![map.next_value_seed(Indices {
                    at: &at,
                    cell: None,
                })?]
            };
            out.insert(name, value);
        }
        Ok(out)
    }
}

/// A list of cells, each a list of point indices (`at`: its key path).
struct Lists<'a> {
    at: &'a str,
}

impl<'de> serde::de::DeserializeSeed<'de> for Lists<'_> {
    type Value = Vec<Vec<usize>>;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for Lists<'_> {
    type Value = Vec<Vec<usize>>;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "a list of cells (lists of point indices) at {}", self.at)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 20));
        loop {
            let cell = Some(out.len());
            match seq.next_element_seed(Indices { at: self.at, cell })? {
                Some(nodes) => out.push(nodes),
                None => return Ok(out),
            }
        }
    }
}

/// A list of point indices: a node set (`at`), or cell `cell` of the list at `at`. The
/// key path is formatted only for an error (a mesh of 10⁷ cells reads without one
/// string per index).
struct Indices<'a> {
    at: &'a str,
    cell: Option<usize>,
}

impl<'de> serde::de::DeserializeSeed<'de> for Indices<'_> {
    type Value = Vec<usize>;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for Indices<'_> {
    type Value = Vec<usize>;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "a list of point indices at {}", self.at)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 20));
        loop {
            let index = Index {
                at: self.at,
                cell: self.cell,
                k: out.len(),
            };
            match seq.next_element_seed(index)? {
                Some(v) => out.push(v),
                None => return Ok(out),
            }
        }
    }
}

/// One point index: an integer ≥ 0; anything else is refused with its key path
/// (`at[cell][k]`, or `at[k]` in a node set).
struct Index<'a> {
    at: &'a str,
    cell: Option<usize>,
    k: usize,
}

impl Index<'_> {
    fn refuse<E: serde::de::Error>(&self, value: impl std::fmt::Display) -> E {
        let at = match self.cell {
            Some(c) => format!("{}[{c}][{}]", self.at, self.k),
            None => format!("{}[{}]", self.at, self.k),
        };
        at_key(
            &at,
            value,
            "is not a point index: expected an integer ≥ 0 (0-based, into mesh.points)",
        )
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for Index<'_> {
    type Value = usize;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for Index<'_> {
    type Value = usize;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "a point index at {}", self.at)
    }
    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<usize, E> {
        usize::try_from(v).map_err(|_| self.refuse(v))
    }
    fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<usize, E> {
        usize::try_from(v).map_err(|_| self.refuse(v))
    }
    fn visit_u128<E: serde::de::Error>(self, v: u128) -> Result<usize, E> {
        usize::try_from(v).map_err(|_| self.refuse(v))
    }
    fn visit_i128<E: serde::de::Error>(self, v: i128) -> Result<usize, E> {
        usize::try_from(v).map_err(|_| self.refuse(v))
    }
    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<usize, E> {
        Err(self.refuse(crate::error::num(v)))
    }
    fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<usize, E> {
        Err(self.refuse(v))
    }
    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<usize, E> {
        Err(self.refuse(format!("\"{}\"", crate::error::excerpt(v))))
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<usize, E> {
        Err(self.refuse("none"))
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, _: A) -> Result<usize, A::Error> {
        Err(self.refuse("a list"))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, _: A) -> Result<usize, A::Error> {
        Err(self.refuse("a table"))
    }
}
