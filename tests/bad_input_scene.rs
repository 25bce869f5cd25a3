//! Bad scene files (issue 12 §2–3): `signorini check` and `signorini run` refuse each with
//! exit code 2 and a message naming the scene file, the key path (or line and column),
//! the value and what was expected. One class of mistake per case.

mod common;

use common::bad::{BOX_MESH, BOX_ON_FLOOR, cli, expect, tmp};

/// (class, edit of BASE: (from, to) replacements, needles)
type Case = (
    &'static str,
    &'static [(&'static str, &'static str)],
    &'static [&'static str],
);

const CASES: &[Case] = &[
    (
        "negative Young's modulus",
        &[("young = 1e6", "young = -1e6")],
        &["bodies[0].material.young", "-1000000", "> 0"],
    ),
    (
        "Poisson ratio 0.5",
        &[("poisson = 0.3", "poisson = 0.5")],
        &["material.poisson", "0.5", "[0, 0.4999999]"],
    ),
    (
        "NaN density",
        &[("density = 1000.0", "density = nan")],
        &["material.density", "NaN"],
    ),
    (
        "zero cell count",
        &[("cells = [1, 1, 1]", "cells = [0, 1, 1]")],
        &["mesh.cells", "[0, 1, 1]", "at least 1"],
    ),
    (
        "absurd generator size",
        &[("cells = [1, 1, 1]", "cells = [100000, 100000, 100000]")],
        &["mesh.cells", "[100000, 100000, 100000]", "memory limit"],
    ),
    (
        "negative box size",
        &[("size = [0.1, 0.1, 0.1]", "size = [0.1, -0.1, 0.1]")],
        &["mesh.size[1]", "-0.1", "> 0"],
    ),
    (
        "non-finite origin",
        &[(
            "size = [0.1, 0.1, 0.1]",
            "size = [0.1, 0.1, 0.1], origin = [0.0, nan, 0.0]",
        )],
        &["mesh.origin[1]", "NaN"],
    ),
    (
        "box asked for tri3",
        &[("cell = \"hex8\"", "cell = \"tri3\"")],
        &["mesh.cell", "tri3", "hex8 or tet4"],
    ),
    (
        "unknown node set",
        &[("nodes = \"z0\"", "nodes = \"top\"")],
        &["contacts[0].nodes", "top", "`z0`", "`boundary`"],
    ),
    (
        "unknown obstacle",
        &[("obstacle = \"floor\"", "obstacle = \"wall\"")],
        &["contacts[0].obstacle", "wall", "names no obstacle"],
    ),
    (
        "unknown body",
        &[("body = \"b\"", "body = \"c\"")],
        &["contacts[0].body", "names no body"],
    ),
    (
        "normal of the wrong dimension",
        &[("normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0]")],
        &["obstacles[0].normal", "3 finite components"],
    ),
    (
        "zero normal",
        &[("normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, 0.0]")],
        &["obstacles[0].normal", "zero vector"],
    ),
    (
        "non-finite obstacle point",
        &[("point = [0.0, 0.0, -0.01]", "point = [0.0, inf, -0.01]")],
        &["obstacles[0].point", "inf"],
    ),
    (
        "zero time step",
        &[("dt = 1e-4", "dt = 0")],
        &["time.dt", "0", "> 0"],
    ),
    (
        "end time below one step",
        &[("t_end = 1e-3", "t_end = 1e-9")],
        &["time.t_end", "1e-9", "one step"],
    ),
    (
        "1e30 steps",
        &[("t_end = 1e-3", "t_end = 1e30")],
        &["time.dt", "1.000e34", "at most 1000000000"],
    ),
    (
        "unknown key",
        &[("[time]\n", "[time]\nfoo = 1\n")],
        &["time.foo", "unknown field"],
    ),
    (
        "unknown generator",
        &[("generator = \"box\"", "generator = \"sphere\"")],
        &["bodies[0].mesh.generator", "sphere", "`box`"],
    ),
    (
        "unknown obstacle type",
        &[("type = \"plane\"", "type = \"cone\"")],
        &["obstacles[0].type", "cone", "`plane`"],
    ),
    (
        "restitution above 1",
        &[(
            "obstacle = \"floor\"\n",
            "obstacle = \"floor\"\nrestitution = 2.0\n",
        )],
        &["contacts[0].restitution", "2", "[0, 1]"],
    ),
    (
        "negative friction",
        &[(
            "obstacle = \"floor\"\n",
            "obstacle = \"floor\"\nfriction = -0.1\n",
        )],
        &["contacts[0].friction", "-0.1"],
    ),
    (
        "negative within",
        &[(
            "obstacle = \"floor\"\n",
            "obstacle = \"floor\"\nwithin = -1.0\n",
        )],
        &["contacts[0].within", "-1"],
    ),
    (
        "within that keeps no node",
        &[(
            "obstacle = \"floor\"\n",
            "obstacle = \"floor\"\nwithin = 1e-9\n",
        )],
        &["contacts[0].within", "1e-9", "nearest is 1.000e-2 m"],
    ),
    (
        "unknown scheme",
        &[("[time]\n", "[scheme]\nkind = \"newmark\"\n[time]\n")],
        &["scheme.kind", "newmark", "`moreau-jean`"],
    ),
    (
        "theta out of range",
        &[("[time]\n", "[scheme]\ntheta = 0.2\n[time]\n")],
        &["scheme.theta", "0.2", "[0.5, 1]"],
    ),
    (
        "zero Newton cap",
        &[(
            "[time]\n",
            "[scheme]\nnewton = { tol = 1e-10, max_iterations = 0 }\n[time]\n",
        )],
        &["scheme.newton.max_iterations", "at least 1"],
    ),
    (
        "negative energy excess",
        &[("[time]\n", "[scheme]\nmax_energy_excess = -0.1\n[time]\n")],
        &["scheme.max_energy_excess", "-0.1", "≥ 0"],
    ),
    (
        "zero history stride",
        &[("[time]\n", "[output]\nhistory_stride = 0\n[time]\n")],
        &["output.history_stride", "at least 1"],
    ),
    (
        "gravity of the wrong dimension",
        &[("[time]\n", "[loads]\ngravity = [0.0, -9.81]\n[time]\n")],
        &["loads.gravity", "3 finite components"],
    ),
    (
        "negative damping",
        &[(
            "material = {",
            "damping = { alpha = -1.0, beta = 0.0 }\nmaterial = {",
        )],
        &["bodies[0].damping.alpha", "-1", "[0, inf)"],
    ),
    (
        "initial velocity of the wrong dimension",
        &[("material = {", "velocity = [1.0, 2.0]\nmaterial = {")],
        &["velocity", "[1.0, 2.0]", "3 finite values"],
    ),
    (
        "unknown fixed set",
        &[("material = {", "fixed = [\"nope\"]\nmaterial = {")],
        &["fixed", "nope", "no such node set"],
    ),
    (
        "contact on fixed nodes",
        &[("material = {", "fixed = [\"z0\"]\nmaterial = {")],
        &["contacts[0].nodes", "is fixed"],
    ),
    (
        "contact nodes held across the plane",
        &[(
            "[[obstacles]]",
            "[[prescribed]]\nbody = \"b\"\nnodes = \"z0\"\nvelocity = [0.0, 0.0, 0.0]\ncomponents = [2]\n[[obstacles]]",
        )],
        &[
            "contacts[0].nodes",
            "holds component 2",
            "free across the plane",
        ],
    ),
    (
        "every node fixed",
        &[
            ("material = {", "fixed = [\"x0\", \"x1\"]\nmaterial = {"),
            (
                "[[contacts]]\nbody = \"b\"\nnodes = \"z0\"\nobstacle = \"floor\"\n",
                "",
            ),
        ],
        &["bodies", "0 free degrees of freedom"],
    ),
    (
        "obstacle of the wrong dimension",
        &[(
            "material = {",
            "formulation = \"plane-strain\"\nmaterial = {",
        )],
        &["obstacles[0].point", "2 finite components"],
    ),
    (
        "missing mesh file",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"file\", path = \"missing.msh\" }",
        )],
        &["missing.msh", "no such file", "scene.toml"],
    ),
    (
        "unknown mesh extension",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"file\", path = \"mesh.stl\" }",
        )],
        &["mesh.stl", "`.stl`", ".msh, .vtu or .vtk"],
    ),
    (
        "rod of zero elements",
        &[
            (
                "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
                "mesh = { generator = \"rod\", elements = 0, length = 1.0, area = 1e-4 }",
            ),
            ("point = [0.0, 0.0, -0.01]", "point = [0.0]"),
            ("normal = [0.0, 0.0, 1.0]", "normal = [1.0]"),
            ("nodes = \"z0\"", "nodes = \"x0\""),
        ],
        &["mesh.elements", "at least 1"],
    ),
    (
        "empty body name",
        &[("name = \"b\"", "name = \"\"")],
        &["bodies[0].name", "needs a name"],
    ),
    (
        "duplicate obstacle name",
        &[(
            "[[contacts]]",
            "[[obstacles]]\nname = \"floor\"\ntype = \"sphere\"\ncenter = [0.0, 0.0, 5.0]\nradius = 1.0\n[[contacts]]",
        )],
        &["obstacles[1].name", "floor", "obstacles[0] has that name"],
    ),
    (
        "duplicate body name",
        &[(
            "[[obstacles]]",
            "[[bodies]]\nname = \"b\"\nmesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }\nmaterial = { young = 1e6, poisson = 0.3, density = 1000.0 }\n[[obstacles]]",
        )],
        &["bodies[1].name", "bodies[0] has that name"],
    ),
    (
        "unused obstacle with a zero radius",
        &[(
            "[[contacts]]",
            "[[obstacles]]\nname = \"ball\"\ntype = \"sphere\"\ncenter = [0.0, 0.0, 5.0]\nradius = 0.0\n[[contacts]]",
        )],
        &["obstacles[1].radius", "0", "> 0"],
    ),
    (
        "unused cylinder with a zero axis",
        &[(
            "[[contacts]]",
            "[[obstacles]]\nname = \"cyl\"\ntype = \"cylinder\"\npoint = [0.0, 0.0, 5.0]\naxis = [0.0, 0.0, 0.0]\nradius = 1.0\n[[contacts]]",
        )],
        &["obstacles[1].axis", "zero vector"],
    ),
    (
        "TOML syntax error",
        &[("t_end = 1e-3", "t_end = = 1e-3")],
        &["line 3, column"],
    ),
    (
        "wrong value type",
        &[("t_end = 1e-3", "t_end = \"soon\"")],
        &["time.t_end", "invalid type: string"],
    ),
    (
        "missing required section",
        &[("[time]\ndt = 1e-4\nt_end = 1e-3\n", "")],
        &["missing field `time`"],
    ),
    (
        "unknown material model",
        &[(
            "density = 1000.0 }",
            "density = 1000.0, model = \"mooney\" }",
        )],
        &[
            "bodies[0].material",
            "unknown variant `mooney`",
            "neo-hookean",
        ],
    ),
    (
        "large-deformation law on a plane-stress body",
        &[
            ("density = 1000.0 }", "density = 1000.0, model = \"svk\" }"),
            (
                "name = \"b\"\n",
                "name = \"b\"\nformulation = { plane-stress = { thickness = 0.01 } }\n",
            ),
        ],
        &[
            "bodies[0].material.model",
            "svk",
            "plane-stress and axisymmetric bodies are linear only",
        ],
    ),
    (
        "Schatzman–Paoli on a nonlinear structure",
        &[
            (
                "density = 1000.0 }",
                "density = 1000.0, model = \"neo-hookean\" }",
            ),
            ("[time]\n", "[scheme]\nkind = \"schatzman-paoli\"\n[time]\n"),
        ],
        &["scheme.kind", "schatzman-paoli", "linear structures only"],
    ),
    (
        "Schatzman–Paoli with a prescribed velocity",
        &[
            ("[time]\n", "[scheme]\nkind = \"schatzman-paoli\"\n[time]\n"),
            (
                "[[contacts]]",
                "[[prescribed]]\nbody = \"b\"\nnodes = \"z1\"\nvelocity = [0.0, 0.0, -1.0]\n[[contacts]]",
            ),
        ],
        &[
            "scheme.kind",
            "schatzman-paoli",
            "does not take prescribed velocities",
        ],
    ),
    (
        "prescribed velocity on a hyperelastic body",
        &[
            (
                "density = 1000.0 }",
                "density = 1000.0, model = \"neo-hookean\" }",
            ),
            (
                "[[contacts]]",
                "[[prescribed]]\nbody = \"b\"\nnodes = \"z1\"\nvelocity = [0.0, 0.0, -1.0]\n[[contacts]]",
            ),
        ],
        &[
            "bodies[0] (b).material.model",
            "neo-hookean",
            "no prescribed velocities",
        ],
    ),
    (
        "probe on an unknown body",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"c\"\nnodes = \"z1\"\ntimes = [1e-4, 5e-4]\n[[contacts]]",
        )],
        &["probes[0].body", "c", "names no body"],
    ),
    (
        "probe on an unknown node set",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"top\"\ntimes = [1e-4, 5e-4]\n[[contacts]]",
        )],
        &["probes[0].nodes", "top", "no such node set"],
    ),
    (
        "probe time past the end",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"z1\"\ntimes = [1e-4, 2e-3]\n[[contacts]]",
        )],
        &["probes[0].times[1]", "0.002", "time.t_end = 0.001"],
    ),
    (
        "probe times not increasing",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"z1\"\ntimes = [5e-4, 1e-4]\n[[contacts]]",
        )],
        &["probes[0].times[1]", "0.0001", "must increase"],
    ),
    (
        "probe without times",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"z1\"\ntimes = []\n[[contacts]]",
        )],
        &["probes[0].times", "0 times", "1 to 100000"],
    ),
    (
        "NaN probe time",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"z1\"\ntimes = [nan]\n[[contacts]]",
        )],
        &["probes[0].times[0]", "NaN"],
    ),
    (
        "two probes of one name",
        &[(
            "[[contacts]]",
            "[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"z1\"\ntimes = [1e-4, 5e-4]\n[[probes]]\nname = \"top\"\nbody = \"b\"\nnodes = \"z1\"\ntimes = [1e-4, 5e-4]\n[[contacts]]",
        )],
        &["probes[1].name", "top", "probes[0] has that name"],
    ),
    (
        "arrays mesh: a node index past the points",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 8]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.cells.hex8[0]", "8", "not a point index", "8 points"],
    ),
    (
        "arrays mesh: a cell with too few nodes",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.cells.hex8[0]", "a hex8 cell has 8 nodes"],
    ),
    (
        "arrays mesh: an unknown cell kind",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { wedge6 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.cells", "wedge6", "not a cell kind"],
    ),
    (
        "arrays mesh: a NaN coordinate",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, nan], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.points[6]", "NaN", "finite"],
    ),
    (
        "arrays mesh: a point with two coordinates in 3-D",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.points[1]", "needs 3 coordinates"],
    ),
    (
        "arrays mesh: a point in no cell",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1], [0.5, 0.5, 0.5]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.points[8]", "in no cell"],
    ),
    (
        "arrays mesh: a node set past the points",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 30] } }",
        )],
        &["mesh.node_sets.z0", "30", "not a point index"],
    ),
    (
        "arrays mesh: no cells",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = {}, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["mesh.cells", "at least one point and one cell"],
    ),
    // issue 48: arrays meshes taken as written, or refused
    (
        "arrays mesh: a node set named all",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3], all = [0] } }",
        )],
        &["mesh.node_sets.all", "1 node(s)", "reserved", "every node"],
    ),
    (
        "arrays mesh: a cell listed twice",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7], [4, 5, 6, 7, 0, 1, 2, 3]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &[
            "mesh.cells.hex8[1]",
            "[4, 5, 6, 7, 0, 1, 2, 3]",
            "mesh.cells.hex8[0]",
            "listed twice",
        ],
    ),
    (
        "arrays mesh: a negative cell index",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, -7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &["bodies[0].mesh.cells.hex8[0][7]", "value -7", "integer ≥ 0"],
    ),
    (
        "arrays mesh: a fractional cell index",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7.5]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &[
            "bodies[0].mesh.cells.hex8[0][7]",
            "value 7.5",
            "integer ≥ 0",
        ],
    ),
    (
        "arrays mesh: a string in a node set",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, \"two\", 3] } }",
        )],
        &["bodies[0].mesh.node_sets.z0[2]", "\"two\"", "point index"],
    ),
    // a body inverted at the start: in its mesh (mirrored, or one tangled corner), or by its displacement
    (
        "arrays mesh: a mirrored cell",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[4, 5, 6, 7, 0, 1, 2, 3]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &[
            "bodies[0] (b).mesh",
            "cell 0 (hex8), corner 0",
            "det J = -1.000e0",
            "reorder the cell's nodes",
        ],
    ),
    (
        "arrays mesh: a tangled corner",
        &[(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.03, 0.03, 0.03], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
        )],
        &[
            "bodies[0] (b).mesh",
            "corner 6",
            "det J = -",
            "reorder the cell's nodes",
        ],
    ),
    (
        "initial displacement that inverts the body",
        &[(
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\ninitial_displacement = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -0.2], [0.0, 0.0, -0.2], [0.0, 0.0, -0.2], [0.0, 0.0, -0.2]]",
        )],
        &[
            "bodies[0] (b).initial_displacement",
            "cell 0 (hex8), corner 0",
            "det F = -1.000e0",
            "inverts the cell",
        ],
    ),
    (
        "initial displacement inverting a quadrature point, not a corner (neo-Hookean)",
        &[
            (
                "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
                "mesh = { generator = \"arrays\", points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], [0.1, 0.1, 0.1], [0.0, 0.1, 0.1]], cells = { hex8 = [[0, 1, 2, 3, 4, 5, 6, 7]] }, node_sets = { z0 = [0, 1, 2, 3] } }",
            ),
            (
                "density = 1000.0 }",
                "density = 1000.0, model = \"neo-hookean\" }\ninitial_displacement = [[0.0, 0.0, 0.0], [-0.072, -0.098, 0.064], [0.0, -0.079, 0.0], [-0.104, 0.0, 0.109], [-0.026, 0.0, -0.057], [0.0, -0.11, 0.0], [0.089, 0.004, 0.0], [0.118, -0.112, 0.0]]",
            ),
        ],
        &[
            "bodies[0] (b).initial_displacement",
            "cell 0: det F = -",
            "at a quadrature point",
            "inverts the cell",
        ],
    ),
    // initial fields and rigid motions taken as written, or refused
    (
        "field file table with an unknown key",
        &[(
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\ninitial_velocity = { file = \"v0.csv\", columns = [0, 1, 2] }",
        )],
        &[
            "bodies[0].initial_velocity.columns",
            "value columns",
            "not a key of a field file",
        ],
    ),
    (
        "field file path of the wrong type",
        &[(
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\ninitial_velocity = { file = 3 }",
        )],
        &[
            "bodies[0].initial_velocity.file`",
            "integer `3`",
            "a string",
        ],
    ),
    (
        "initial velocity field of the wrong type",
        &[(
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\ninitial_velocity = 3",
        )],
        &[
            "bodies[0].initial_velocity",
            "integer `3`",
            "rows of numbers",
        ],
    ),
    (
        "a spin on a body with fixed nodes",
        &[(
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
            "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\nangular_velocity = [0.0, 0.0, 10.0]\nfixed = [\"x0\"]",
        )],
        &[
            "bodies[0] (b).angular_velocity",
            "at node 0 component 0",
            "must be 0 on every fixed component",
        ],
    ),
    (
        "initial velocity on prescribed nodes",
        &[
            (
                "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
                "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\ninitial_velocity = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]",
            ),
            (
                "[[obstacles]]",
                "[[prescribed]]\nbody = \"b\"\nnodes = \"z1\"\nvelocity = [0.0, 0.0, 0.0]\n[[obstacles]]",
            ),
        ],
        &[
            "bodies[0] (b).initial_velocity",
            "value 1 at node 4",
            "prescribed[0] drives that component",
            "starts at 0",
        ],
    ),
    (
        "initial displacement on prescribed nodes",
        &[
            (
                "material = { young = 1e6, poisson = 0.3, density = 1000.0 }",
                "material = { young = 1e6, poisson = 0.3, density = 1000.0 }\ninitial_displacement = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.001], [0.0, 0.0, 0.001], [0.0, 0.0, 0.001], [0.0, 0.0, 0.001]]",
            ),
            (
                "[[obstacles]]",
                "[[prescribed]]\nbody = \"b\"\nnodes = \"z1\"\nvelocity = [0.0, 0.0, 0.0]\ncomponents = [2]\n[[obstacles]]",
            ),
        ],
        &[
            "bodies[0] (b).initial_displacement",
            "value 0.001 at node 4",
            "prescribed[0] drives that component",
        ],
    ),
    // issue 48: validated before any flush of subnormals; loads whose arithmetic overflows
    (
        "a subnormal end time",
        &[("t_end = 1e-3", "t_end = 5e-320")],
        &[
            "time.t_end",
            "value 5e-320",
            "at least one step (time.dt = 0.0001)",
        ],
    ),
    (
        "a load of 1e308",
        &[(
            "[[obstacles]]",
            "[[forces]]\nbody = \"b\"\nnodes = \"z1\"\ntotal = [0.0, 0.0, -1e308]\n[[obstacles]]",
        )],
        &["forces[0].total", "-1e308", "at most 1e150 N", "overflow"],
    ),
    (
        "an initial velocity of 1e308",
        &[(
            "density = 1000.0 }",
            "density = 1000.0 }\nvelocity = [0.0, 0.0, -1e308]",
        )],
        &[
            "bodies[0] (b).velocity",
            "-1e308 m/s",
            "at most 1e150 m/s",
            "overflow",
        ],
    ),
    (
        "an initial displacement of 1e300",
        &[(
            "density = 1000.0 }",
            "density = 1000.0 }\ninitial_displacement = [[1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [1e300, 0.0, 0.0]]",
        )],
        &[
            "bodies[0] (b).initial_displacement",
            "1e300 m",
            "at most 1e150 m",
        ],
    ),
    (
        "a load pushed past the bound by its time factors",
        &[(
            "[[obstacles]]",
            "[[forces]]\nbody = \"b\"\nnodes = \"z1\"\ntotal = [0.0, 0.0, -1e100]\ntime = [[0.0, 0.0], [1.0, 1e60]]\n[[obstacles]]",
        )],
        &["forces[0].total", "reaches 1e160 N", "at most 1e150 N"],
    ),
    (
        "pressure on no body",
        &[(
            "[[obstacles]]",
            "[[pressures]]\nbody = \"c\"\nfaces = \"z1\"\npressure = 1e3\n[[obstacles]]",
        )],
        &["pressures[0].body", "c", "names no body"],
    ),
    (
        "NaN pressure",
        &[(
            "[[obstacles]]",
            "[[pressures]]\nbody = \"b\"\nfaces = \"z1\"\npressure = nan\n[[obstacles]]",
        )],
        &["pressures[0].pressure", "NaN", "finite pressure"],
    ),
    (
        "pressure of 1e200",
        &[(
            "[[obstacles]]",
            "[[pressures]]\nbody = \"b\"\nfaces = \"z1\"\npressure = 1e200\n[[obstacles]]",
        )],
        &["pressures[0].pressure", "at most 1e150 Pa"],
    ),
    (
        "pressure on an unknown face set",
        &[(
            "[[obstacles]]",
            "[[pressures]]\nbody = \"b\"\nfaces = \"lid\"\npressure = 1e3\n[[obstacles]]",
        )],
        &["pressures[0].faces", "lid", "no such node set"],
    ),
    (
        "gravity of 1e200",
        &[(
            "[[obstacles]]",
            "[loads]\ngravity = [0.0, 0.0, -1e200]\n[[obstacles]]",
        )],
        &["loads.gravity", "-1e200", "at most 1e150"],
    ),
    (
        "unknown output encoding",
        &[("[time]\n", "[output]\nencoding = \"xml\"\n[time]\n")],
        &["output.encoding", "unknown variant `xml`"],
    ),
];

#[test]
fn each_bad_scene_is_refused_with_its_key_and_value() {
    let dir = tmp("scenes");
    assert!(CASES.len() >= 45);
    for (class, edits, needles) in CASES {
        let mut text = BOX_ON_FLOOR.replace("MESH", BOX_MESH);
        for (from, to) in *edits {
            assert!(
                text.contains(from),
                "{class}: the edit {from:?} does not apply"
            );
            text = text.replace(from, to);
        }
        std::fs::write(dir.join("scene.toml"), &text).unwrap();
        let mut want: Vec<&str> = vec!["scene.toml"];
        want.extend_from_slice(needles);
        // `check` and `run` agree: both refuse, with the same message
        let c = cli(&dir, &["check", "scene.toml"], &[]);
        expect(class, c.clone(), 2, &want);
        let r = cli(&dir, &["run", "scene.toml", "--quiet", "--out", "out"], &[]);
        assert_eq!(r.0, 2, "{class}: run exit {}: {}", r.0, r.1);
        assert_eq!(
            c.1.lines().last(),
            r.1.lines().last(),
            "{class}: check and run differ"
        );
    }
}

#[test]
fn scene_inputs_that_are_not_files_are_refused_without_reading() {
    let dir = tmp("notfiles");
    // a FIFO would block a reader forever; /dev/zero would fill the memory
    let fifo = dir.join("fifo.toml");
    let ok = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if ok {
        expect(
            "FIFO scene",
            cli(&dir, &["check", "fifo.toml"], &[]),
            2,
            &["fifo.toml", "not a regular file"],
        );
    }
    expect(
        "device scene",
        cli(&dir, &["check", "/dev/zero"], &[]),
        2,
        &["/dev/zero", "not a regular file"],
    );
    std::fs::create_dir_all(dir.join("d.toml")).unwrap();
    expect(
        "directory scene",
        cli(&dir, &["check", "d.toml"], &[]),
        2,
        &["d.toml", "a directory"],
    );
    std::fs::write(dir.join("bin.toml"), [0x5b, 0xff, 0xfe, 0x0a]).unwrap();
    expect(
        "non-UTF-8 scene",
        cli(&dir, &["check", "bin.toml"], &[]),
        2,
        &["bin.toml", "line 1", "not UTF-8"],
    );
    expect(
        "missing scene",
        cli(&dir, &["check", "nope.toml"], &[]),
        2,
        &["nope.toml", "no such file"],
    );
    // a mesh file that is a FIFO
    if ok {
        let mesh_fifo = dir.join("m.msh");
        Command::new("mkfifo").arg(&mesh_fifo).status().unwrap();
        let scene = BOX_ON_FLOOR.replace("MESH", BOX_MESH).replace(
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }",
            "mesh = { generator = \"file\", path = \"m.msh\" }",
        );
        std::fs::write(dir.join("s.toml"), scene).unwrap();
        expect(
            "FIFO mesh",
            cli(&dir, &["check", "s.toml"], &[]),
            2,
            &["m.msh", "not a regular file", "s.toml"],
        );
    }
}

use std::process::Command;

/// Issue 16 §6: friction on a 1-D rod was silently dropped (`check` said "friction
/// none"); now `check` and `run` refuse it, naming the contact's key.
#[test]
fn friction_on_a_rod_is_refused() {
    let dir = tmp("rodfriction");
    let bar = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/bar.toml"),
    )
    .unwrap()
    .replace("restitution = 0.0", "restitution = 0.0\nfriction = 0.3")
    .replace("elements = 1000", "elements = 10");
    std::fs::write(dir.join("rod.toml"), bar).unwrap();
    for cmd in ["check", "run"] {
        expect(
            "friction on a rod",
            cli(&dir, &[cmd, "rod.toml", "--quiet"], &[]),
            2,
            &[
                "rod.toml",
                "contacts[0].friction",
                "0.3",
                "no tangential direction",
            ],
        );
    }
}

/// Issue 16 §6: `[[forces]]`, `[[prescribed]]`, `[loads]` and `[reference]` in an
/// `[example]` scene were accepted and silently ignored; each is refused by name.
#[test]
fn tables_an_example_scene_would_ignore_are_refused() {
    let dir = tmp("example-extra");
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/bouncing_ball.toml"),
    )
    .unwrap();
    for (key, table) in [
        (
            "forces",
            "[[forces]]\nbody = \"ball\"\nnodes = \"all\"\ntotal = [1.0]\n",
        ),
        (
            "prescribed",
            "[[prescribed]]\nbody = \"ball\"\nnodes = \"all\"\nvelocity = [1.0]\n",
        ),
        ("loads", "[loads]\ngravity = [-9.81]\n"),
        (
            "probes",
            "[[probes]]\nname = \"p\"\nbody = \"ball\"\nnodes = \"all\"\ntimes = [1.0]\n",
        ),
        (
            "reference",
            "[reference.impacting_bar]\nlength = 1.0\narea = 1e-4\nyoung = 2e11\ndensity = 7800.0\nvelocity = -0.1\n",
        ),
    ] {
        let file = format!("{key}.toml");
        std::fs::write(dir.join(&file), format!("{base}\n{table}")).unwrap();
        expect(
            key,
            cli(&dir, &["check", &file, "--quiet"], &[]),
            2,
            &[
                &file,
                key,
                "in an [example] scene",
                "[example], [time], [scheme] and [output]",
            ],
        );
    }
}

/// `--set KEY=VALUE` overrides a scene key before validation (`check` names the Newton
/// variant it selected); a malformed override, a missing array entry and a misspelt key
/// are refused with exit 2, naming the override or the key path.
#[test]
fn set_overrides_are_applied_and_checked() {
    let dir = tmp("set");
    let text = BOX_ON_FLOOR.replace("MESH", BOX_MESH).replace(
        "density = 1000.0 }",
        "density = 1000.0, model = \"neo-hookean\" }",
    );
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    let (code, _) = cli(
        &dir,
        &[
            "check",
            "scene.toml",
            "--set",
            "scheme.newton.modified=true",
        ],
        &[],
    );
    assert_eq!(code, 0);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(&dir)
        .args([
            "check",
            "scene.toml",
            "--set",
            "scheme.newton.modified=true",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("modified Newton"), "{stdout}");
    for (set, needles) in [
        ("scheme.newton.modified", &["--set", "KEY=VALUE"][..]),
        ("scheme.theta=half", &["--set", "not one TOML value"][..]),
        // issue 34: the rest of the value was dropped and the run went on
        (
            "time.dt=2e-6\n[evil]\nx = 1",
            &["--set", "not one TOML value", "no line breaks"][..],
        ),
        (
            "bodies[2].velocity=[0.0, 0.0, 1.0]",
            &["--set", "no [2]"][..],
        ),
        (
            "scheme.newtn=1",
            &["scene.toml", "scheme.newtn", "unknown field"][..],
        ),
        (
            "bodies[0].material.model=\"mooney\"",
            &["bodies[0].material.model", "mooney"][..],
        ),
    ] {
        let r = cli(&dir, &["check", "scene.toml", "--set", set], &[]);
        expect(set, r, 2, needles);
    }
}

/// The slider–crank example's parameters (`[example] kind = "slider-crank"`) are checked
/// like every scene value: exit 2 naming the key path, the value and the expectation.
#[test]
fn slider_crank_parameters_are_checked() {
    let dir = tmp("slider-crank");
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/slider_crank.toml");
    let scene = scene.to_str().unwrap();
    for (set, needles) in [
        (
            "example.mechanism.j2=-1.0",
            &["example.mechanism.j2", "-1", "> 0"][..],
        ),
        ("example.mechanism.c=nan", &["example.mechanism.c", "NaN"]),
        (
            "example.restitution=1.5",
            &["example.restitution", "1.5", "[0, 1]"],
        ),
        ("example.v0=[1.0, nan, 0.0]", &["example.v0[1]", "NaN"]),
        ("example.friction=-0.1", &["example.friction", "-0.1"]),
        ("example.mechanism.j4=1.0", &["example", "j4", "`j2`"]),
    ] {
        expect(
            set,
            cli(&dir, &["check", scene, "--set", set, "--quiet"], &[]),
            2,
            needles,
        );
    }
}

/// An axisymmetric body takes linear materials only: a large-deformation law is refused
/// with exit 2, naming the key, the law and the formulations that take it.
#[test]
fn large_deformation_on_an_axisymmetric_body_is_refused() {
    let dir = tmp("axisymmetric-svk");
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/hertz_ball.toml");
    expect(
        "axisymmetric svk",
        cli(
            &dir,
            &[
                "check",
                scene.to_str().unwrap(),
                "--set",
                "bodies[0].material.model=\"svk\"",
                "--quiet",
            ],
            &[],
        ),
        2,
        &[
            "bodies[0].material.model",
            "svk",
            "axisymmetric",
            "linear only",
        ],
    );
}

/// The energy–momentum option is a midpoint rule: with θ ≠ 1/2 it is refused with exit 2,
/// naming the key, the value and the θ it needs.
#[test]
fn energy_momentum_needs_the_midpoint() {
    let dir = tmp("energy-momentum-theta");
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/ball_crush.toml");
    expect(
        "energy-momentum at theta 0.6",
        cli(
            &dir,
            &[
                "check",
                scene.to_str().unwrap(),
                "--set",
                "scheme.energy_momentum=true",
                "--set",
                "scheme.theta=0.6",
                "--quiet",
            ],
            &[],
        ),
        2,
        &["scheme.energy_momentum", "true", "theta = 0.5", "0.6"],
    );
}

/// Contacts between bodies (issue 18): each mistake refused with exit 2, naming the key,
/// the value and what was expected.
#[test]
fn bad_contacts_between_bodies_are_refused() {
    const TWO_BOXES: &str = r#"[time]
dt = 1e-4
t_end = 1e-3
[[bodies]]
name = "a"
mesh = { generator = "box", cell = "hex8", cells = [2, 2, 1], size = [0.1, 0.1, 0.1], origin = [0.0, 0.0, 0.1] }
material = { young = 1e6, poisson = 0.3, density = 1000.0 }
[[bodies]]
name = "b"
mesh = { generator = "box", cell = "hex8", cells = [3, 3, 1], size = [0.1, 0.1, 0.1] }
material = { young = 1e6, poisson = 0.3, density = 1000.0 }
fixed = ["z0"]
[[contacts]]
body = "a"
nodes = "z0"
target = { body = "b", surface = "z1" }
"#;
    let cases: &[(&str, (&str, &str), &[&str])] = &[
        (
            "unknown target body",
            ("body = \"b\", surface", "body = \"c\", surface"),
            &["contacts[0].target.body", "value c", "names no body"],
        ),
        (
            "self-contact",
            ("body = \"b\", surface", "body = \"a\", surface"),
            &["contacts[0].target.body", "self-contact is not modelled"],
        ),
        (
            "obstacle and target",
            ("nodes = \"z0\"", "nodes = \"z0\"\nobstacle = \"floor\""),
            &["contacts[0]", "obstacle and target", "give one"],
        ),
        (
            "unknown surface set",
            ("surface = \"z1\"", "surface = \"top\""),
            &["contacts[0].target.surface", "top", "no such node set"],
        ),
        (
            "negative search distance",
            ("surface = \"z1\"", "surface = \"z1\", search = -1.0"),
            &["contacts[0].target.search", "-1", "> 0"],
        ),
        (
            "zero capacity",
            ("surface = \"z1\"", "surface = \"z1\", capacity = 0"),
            &["contacts[0].target.capacity", "0", "1..=4096"],
        ),
        (
            "unknown pairing",
            ("surface = \"z1\"", "surface = \"z1\", pairing = \"mortar\""),
            &["pairing", "mortar"],
        ),
        (
            "node-to-node on non-matching meshes",
            (
                "surface = \"z1\"",
                "surface = \"z1\", pairing = \"node-to-node\"",
            ),
            &[
                "contacts[0].target.pairing",
                "node-to-node",
                "do not match",
                "node-to-surface",
            ],
        ),
        (
            "too few candidates kept",
            (
                "surface = \"z1\"",
                "surface = \"z1\", search = 0.2, capacity = 2",
            ),
            &["contacts[0].target.search", "candidate facets", "capacity"],
        ),
    ];
    let dir = tmp("bodies");
    for (class, (from, to), needles) in cases {
        assert!(TWO_BOXES.contains(from), "{class}");
        let text = TWO_BOXES.replace(from, to);
        std::fs::write(dir.join("scene.toml"), &text).unwrap();
        let mut want = vec!["scene.toml"];
        want.extend_from_slice(needles);
        expect(class, cli(&dir, &["check", "scene.toml"], &[]), 2, &want);
    }
    // a node that moves more than half the search distance in a step could cross a
    // facet the lists missed: the run stops (exit 1) naming the parameter
    let fast = TWO_BOXES
        .replace("surface = \"z1\"", "surface = \"z1\", search = 1e-3")
        .replace(
            "origin = [0.0, 0.0, 0.1] }",
            "origin = [0.0, 0.0, 0.1] }\nvelocity = [0.0, 0.0, -10.0]",
        );
    std::fs::write(dir.join("fast.toml"), &fast).unwrap();
    expect(
        "a step longer than the search",
        cli(&dir, &["run", "fast.toml", "--quiet", "--out", "out"], &[]),
        1,
        &["target.search", "in one step", "smaller time step"],
    );
    // the good scene passes, and `check` shows the contact entry and its search
    std::fs::write(dir.join("scene.toml"), TWO_BOXES).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(&*dir)
        .args(["check", "scene.toml"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("contact entry") && text.contains("9 nodes of \"a\" against 9 facets"),
        "{text}"
    );
}

/// Issue 34's vague or silent refusals, each in the user's terms: a time point with a
/// third number, an empty node set, an axisymmetric scene with gravity along r or a
/// plane-strain neighbour, a 3-D mesh given a 2-D formulation, `max_active_rows`
/// below one frictional block, and the examples' starting states.
#[test]
fn issue_34_refusals_name_what_the_user_wrote() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tmp("issue34");
    let check = |file: &str, sets: &[&str]| {
        let mut a = vec!["check", file];
        for s in sets {
            a.extend(["--set", s]);
        }
        cli(root, &a, &[])
    };
    // forces[].time with three numbers: the third was dropped
    let text = BOX_ON_FLOOR.replace("MESH", BOX_MESH)
        + "[[forces]]\nbody = \"b\"\nnodes = \"z1\"\ntotal = [0.0, 0.0, -1.0]\n\
           time = [[0.0, 0.0, 5.0], [1.0, 1.0]]\n";
    std::fs::write(dir.join("force.toml"), &text).unwrap();
    expect(
        "time point of three",
        cli(&dir, &["check", "force.toml"], &[]),
        2,
        &["forces[0].time", "time point 0 has 3 number(s), expected 2"],
    );
    // a node set that is empty: a VTK point-data flag that is 0 on every node
    std::fs::write(
        dir.join("m.vtk"),
        "# vtk DataFile Version 5.1\nm\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n\
         0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY \
         vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS empty int 1\n\
         LOOKUP_TABLE default\n0 0 0 0\nSCALARS base int 1\nLOOKUP_TABLE default\n1 1 1 0\n",
    )
    .unwrap();
    let text = "[time]\ndt = 1e-4\nt_end = 1e-3\n[[bodies]]\nname = \"b\"\n\
                mesh = { generator = \"file\", path = \"m.vtk\" }\n\
                material = { young = 1e6, poisson = 0.3, density = 1000.0 }\n\
                fixed = [\"empty\"]\n";
    std::fs::write(dir.join("empty.toml"), text).unwrap();
    expect(
        "empty fixed set",
        cli(&dir, &["check", "empty.toml"], &[]),
        2,
        &["fixed.nodes", "value empty", "the node set is empty"],
    );
    // axisymmetric: gravity along r, a plane-strain neighbour, a 3-D mesh
    expect(
        "gravity along r",
        check("meshes/hertz_ball.toml", &["loads.gravity=[-9.81, 0.0]"]),
        2,
        &["loads.gravity", "axis of revolution"],
    );
    expect(
        "a plane not normal to the axis",
        check(
            "meshes/hertz_ball.toml",
            &["obstacles[0].normal=[0.6, 0.8]"],
        ),
        2,
        &["obstacles[0].normal", "[0.6, 0.8]", "normal to the axis"],
    );
    expect(
        "plane-strain beside axisymmetric",
        check(
            "meshes/hertz_ball_on_plate.toml",
            &["bodies[1].formulation=\"plane-strain\""],
        ),
        2,
        &[
            "bodies[1].formulation",
            "plane-strain",
            "must be axisymmetric",
        ],
    );
    let text = "[time]\ndt = 1e-4\nt_end = 1e-3\n[[bodies]]\nname = \"b\"\n\
                mesh = { generator = \"box\", cell = \"tet4\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }\n\
                formulation = \"axisymmetric\"\n\
                material = { young = 1e6, poisson = 0.3, density = 1000.0 }\n";
    std::fs::write(dir.join("axi.toml"), text).unwrap();
    expect(
        "tet4 given axisymmetric",
        cli(&dir, &["check", "axi.toml"], &[]),
        2,
        &[
            "formulation",
            "axisymmetric",
            "cell 0 of the mesh is tet4",
            "formulation = \"solid\"",
        ],
    );
    expect(
        "3-D obstacle in a 2-D scene",
        check(
            "meshes/ball_drop.toml",
            &["bodies[0].formulation=\"axisymmetric\""],
        ),
        2,
        &[
            "obstacles[0].point",
            "(in a 2-D scene: bodies[0] has formulation = \"axisymmetric\")",
        ],
    );
    // a mesh node is named by its file tag and file, not by its internal index
    let ball = root.join("meshes/ball.msh");
    let text = format!(
        "[time]\ndt = 1e-4\nt_end = 1e-3\n[[bodies]]\nname = \"ball\"\n\
         mesh = {{ generator = \"file\", path = {:?} }}\n\
         material = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}\n\
         [[obstacles]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0.0, 0.0, -0.06]\n\
         normal = [0.0, 0.0, 1.0]\n\
         [[contacts]]\nbody = \"ball\"\nnodes = \"surface\"\nobstacle = \"floor\"\n\
         [[contacts]]\nbody = \"ball\"\nnodes = \"surface\"\nobstacle = \"floor\"\n",
        ball.to_str().unwrap()
    );
    std::fs::write(dir.join("twice.toml"), text).unwrap();
    expect(
        "a node twice",
        cli(&dir, &["check", "twice.toml"], &[]),
        2,
        &[
            "contacts[1]",
            "(tag in ball.msh)",
            "already meets obstacle \"floor\"",
        ],
    );
    // one frictional 3-D block is 3 rows
    expect(
        "max_active_rows 2",
        check("meshes/sliding_block.toml", &["scheme.max_active_rows=2"]),
        2,
        &[
            "scheme.max_active_rows",
            "2",
            "at least one contact block (3 rows",
        ],
    );
    // the examples' starting states
    expect(
        "v0 = 1e308",
        check("meshes/bouncing_ball.toml", &["example.v0=1e308"]),
        2,
        &["example.v0", "initial kinetic energy of inf J"],
    );
    expect(
        "slider inside its guides",
        check(
            "meshes/slider_crank.toml",
            &["example.q0=[0.0, 0.0, -0.05]"],
        ),
        2,
        &["example.q0", "contact 0 starts 1.468e-3 m inside"],
    );
}

/// Issue 48: a field file's row `1.0,,0.0,-1.0` read as (1, 0, −1); now its empty cell
/// is refused with file, line and column. A file of NUL bytes is quoted in one short
/// excerpt, not echoed whole.
#[test]
fn field_files_are_read_as_written() {
    let dir = tmp("field_files");
    let scene = BOX_ON_FLOOR.replace("MESH", BOX_MESH).replace(
        "density = 1000.0 }",
        "density = 1000.0 }\ninitial_velocity = { file = \"v0.csv\" }",
    );
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    std::fs::write(dir.join("v0.csv"), "0 0 0\n1.0,,0.0,-1.0\n").unwrap();
    expect(
        "an empty cell",
        cli(&dir, &["check", "scene.toml"], &[]),
        2,
        &[
            "v0.csv:line 2, column 5",
            "an empty cell",
            "`1.0,,0.0,-1.0`",
        ],
    );
    std::fs::write(dir.join("v0.csv"), "0, 0, 0,\n").unwrap();
    expect(
        "a trailing comma",
        cli(&dir, &["check", "scene.toml"], &[]),
        2,
        &["v0.csv:line 1, column 9", "an empty cell"],
    );
    // the same rows, well written, are taken (commas with spaces, or white space)
    let rows = "0.0, 0.0, 0.0\n".repeat(4) + &"0 0 -1.0 # falling\n".repeat(4);
    std::fs::write(dir.join("v0.csv"), rows).unwrap();
    let (code, err) = cli(&dir, &["check", "scene.toml"], &[]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(dir.join("v0.csv"), vec![0u8; 20 << 20]).unwrap();
    let (code, err) = cli(&dir, &["check", "scene.toml"], &[]);
    expect(
        "a file of NUL bytes",
        (code, err.clone()),
        2,
        &[
            "v0.csv:line 1",
            "\\u{0}",
            "(20971520 bytes)",
            "is not a finite number",
        ],
    );
    assert!(
        err.len() < 400,
        "the NUL file is echoed: {} bytes",
        err.len()
    );
}
