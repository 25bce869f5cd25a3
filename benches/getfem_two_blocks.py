#!/usr/bin/python3
"""Two elastic blocks in contact over a full face, in GetFEM 5.4 (Debian's python3-getfem,
run with /usr/bin/python3), side by side with signorini (issue 18, Performance).

Two 0.1 m cubes of N x N x N hex8 cells (E = 1e7 Pa, nu = 0.3, rho = 1000 kg/m3): the
lower one held on its bottom face (z = 0), the upper one resting on it (its bottom face
at z = 0.1 m on the lower one's top face) and launched down at 1 m/s; h = 1e-5 s,
`--steps` steps (default 50, as the GetFEM peer's cube case). The same problem as
`python3 benches/getfem_two_blocks.py --signorini-scene N` writes for signorini.

GetFEM model, its fastest path for this problem as the peer scripts in
../shared/peers/getfem measured it (MUMPS, consistent mass, Newmark beta = 1/4):
  * Q1 (FEM_QK(3,1)) displacement on each cube ('cartesian' mesh), 2x2x2 Gauss;
  * isotropic linearized elasticity and mass bricks, Newmark scheme on u1 and u2;
  * the lower cube's bottom face held by a Dirichlet condition (multipliers);
  * add_nodal_contact_between_nonmatching_meshes_brick: the upper cube's bottom face
    (slave) against the lower cube's top face (master), symmetric Alart-Curnier
    augmented Lagrangian (version 2), r = E x cell size;
  * one md.solve() (GetFEM's Newton) per step, max_res 1e-8, max_iter 10.
Set-up (meshes, fems, model, bricks) and the stepping loop are timed separately
(time.perf_counter); peak memory is the process's ru_maxrss. Prints one JSON line.

`--scaling --signorini BIN` runs signorini alone on two families of blocks, cubes of
N³ cells (N = 6 … 20: dofs ∝ N³, contacts ∝ N²) and blocks of a 12 × 12-cell face
N cells thick (N = 6 … 48: contacts fixed), and fits log y = a + b log(dofs) +
c log(contacts) by least squares for the set-up, the time per step and the peak memory;
`--delassus flexibility` keeps every run on one Delassus path (`auto` switches from the
full contact zone to its flexibilities where the `n × z` blocks pass 2 GiB).

`--pairs K --signorini BIN` runs the comparison itself: K pairs, each GetFEM (this
script in a child process) then signorini (`BIN run` on the same scene, its set-up being
`model_seconds + integrator_seconds` and its step `seconds_per_step` of summary.json,
its peak the summary's VmHWM), and prints the medians and the per-step ratio, one JSON
line per run and a table at the end. Run it on a quiet machine.
"""
import argparse
import json
import resource
import sys
import time

E, NU, RHO, V0, SIDE, H = 1e7, 0.3, 1000.0, 1.0, 0.1, 1e-5


def scene(n, steps, depth=None):
    """The signorini scene of the same problem (node-to-surface, both bodies deformable);
    `depth` cells across the thickness of each block (default n: cubes), the block then
    SIDE * depth / n thick."""
    d = n if depth is None else depth
    t = SIDE * d / n
    return f"""# Two {n}x{n}x{d}-cell hex8 blocks in contact over a full face (benches/getfem_two_blocks.py)
[time]
dt = {H:e}
t_end = {steps * H:e}

[scheme]
kind = "combined-projection"

[[bodies]]
name = "lower"
mesh = {{ generator = "box", cell = "hex8", cells = [{n}, {n}, {d}], size = [{SIDE}, {SIDE}, {t}] }}
material = {{ young = {E:e}, poisson = {NU}, density = {RHO} }}
fixed = ["z0"]

[[bodies]]
name = "upper"
mesh = {{ generator = "box", cell = "hex8", cells = [{n}, {n}, {d}], size = [{SIDE}, {SIDE}, {t}], origin = [0.0, 0.0, {t}] }}
material = {{ young = {E:e}, poisson = {NU}, density = {RHO} }}
velocity = [0.0, 0.0, -{V0}]

[[contacts]]
body = "upper"
nodes = "z0"
target = {{ body = "lower", surface = "z1" }}
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--cells', type=int, default=20)
    ap.add_argument('--steps', type=int, default=50)
    ap.add_argument('--lsolver', default='mumps')
    ap.add_argument('--signorini-scene', action='store_true', help='print the signorini scene and exit')
    ap.add_argument('--pairs', type=int, default=0, help='run K GetFEM/signorini pairs in turn and print medians')
    ap.add_argument('--signorini', default='target/release/signorini', help='the signorini binary (with --pairs, --scaling)')
    ap.add_argument('--scaling', action='store_true', help='signorini alone on two families of blocks: exponents')
    ap.add_argument('--delassus', default='', help='with --scaling: scheme.delassus for every run (default: the scene\'s auto)')
    args = ap.parse_args()
    n = args.cells
    if args.signorini_scene:
        sys.stdout.write(scene(n, args.steps))
        return
    if args.pairs > 0:
        compare(args)
        return
    if args.scaling:
        scaling(args)
        return
    import numpy as np
    import getfem as gf
    gf.util_trace_level(0)
    gf.util_warning_level(0)

    t0 = time.perf_counter()
    lam = E * NU / ((1 + NU) * (1 - 2 * NU))
    mu = E / (2 * (1 + NU))
    md = gf.Model('real')
    for name in ['lambda', 'mu', 'rho']:
        md.add_initialized_data(name, [{'lambda': lam, 'mu': mu, 'rho': RHO}[name]])
    meshes, fems, ims = [], [], []
    for b, z0 in enumerate([0.0, SIDE]):
        g = [np.linspace(0.0, SIDE, n + 1), np.linspace(0.0, SIDE, n + 1), np.linspace(z0, z0 + SIDE, n + 1)]
        m = gf.Mesh('cartesian', *g)
        mf = gf.MeshFem(m, 3)
        mf.set_classical_fem(1)
        mim = gf.MeshIm(m, gf.Integ('IM_GAUSS_PARALLELEPIPED(3,3)'))
        border = m.outer_faces()
        nrm = m.normal_of_faces(border)
        m.set_region(1, border[:, np.nonzero(nrm[2] < -0.5)[0]])   # bottom face
        m.set_region(2, border[:, np.nonzero(nrm[2] > 0.5)[0]])    # top face
        u = f'u{b + 1}'
        md.add_fem_variable(u, mf)
        md.add_isotropic_linearized_elasticity_brick(mim, u, 'lambda', 'mu')
        md.add_Newmark_scheme(u, 0.25, 0.5)
        md.add_mass_brick(mim, f'Dot2_{u}', 'rho')
        meshes.append(m)
        fems.append(mf)
        ims.append(mim)
    md.add_Dirichlet_condition_with_multipliers(ims[0], 'u1', fems[0], 1)
    slave = fems[1].basic_dof_on_region(1)
    ncontact = len(slave) // 3
    md.add_initialized_data('r', [E * SIDE / n])
    md.add_nodal_contact_between_nonmatching_meshes_brick(ims[1], ims[0], 'u2', 'u1', 'lambda_n', 'r', 1, 2, 1, 0, 2)
    md.set_time_step(H)
    ncontact = md.variable('lambda_n').size
    dofs = 0
    for b, mf in enumerate(fems):
        k = mf.nbdof()
        dofs += k
        v0 = np.zeros(k)
        if b == 1:
            v0[2::3] = -V0
        u = f'u{b + 1}'
        md.set_variable(u, np.zeros(k))
        md.set_variable(f'Previous_{u}', np.zeros(k))
        md.set_variable(f'Previous_Dot_{u}', v0)
        md.set_variable(f'Previous_Dot2_{u}', np.zeros(k))
    opts = ['max_res', 1e-8, 'max_iter', 10, 'lsearch', 'simplest', 'lsolver', args.lsolver]
    setup = time.perf_counter() - t0
    steps = np.zeros(args.steps)
    iters = []
    force = []
    t1 = time.perf_counter()
    for k in range(args.steps):
        ts = time.perf_counter()
        it, _ = md.solve(*opts)
        iters.append(it)
        force.append(-float(np.sum(md.variable('lambda_n'))))
        md.shift_variables_for_time_integration()
        steps[k] = time.perf_counter() - ts
    loop = time.perf_counter() - t1
    print(json.dumps({
        'code': 'getfem', 'cells_per_block': n, 'dofs': dofs, 'contacts': ncontact, 'steps': args.steps,
        'setup_seconds': setup, 'seconds_per_step': loop / args.steps,
        'median_step_seconds': float(np.median(steps)), 'first_step_seconds': float(steps[0]),
        'newton_iterations_mean': float(np.mean(iters)),
        'peak_rss_mib': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        'force_last': force[-1],
    }), flush=True)


def run_signorini(binary, text, tmp, tag, sets=()):
    """Runs `binary run` on the scene `text` (with `--set` for each of `sets`); its
    summary as the JSON row of compare()."""
    import os
    import subprocess
    path = os.path.join(tmp, f'{tag}.toml')
    with open(path, 'w') as f:
        f.write(text)
    res = os.path.join(tmp, tag)
    extra = [a for kv in sets for a in ('--set', kv)]
    subprocess.run([binary, 'run', path, '--no-fields', '--no-plots', '--out', res] + extra,
                   check=True, capture_output=True)
    with open(os.path.join(res, 'summary.json')) as f:
        s = json.load(f)
    return {'code': 'signorini', 'dofs': s['dofs'],
            'steps': s['steps'], 'setup_seconds': s['model_seconds'] + s['integrator_seconds'],
            'seconds_per_step': s['seconds_per_step'],
            'newton_iterations_mean': s['iterations']['newton']['mean'],
            'peak_rss_mib': s['peak_memory_bytes'] / 2**20, 'max_violation': s['max_violation']}


def scaling(args):
    """Set-up, step and memory against dofs and contacts: least-squares exponents."""
    import tempfile
    import numpy as np
    runs = [(n, n) for n in (6, 8, 10, 12, 16, 20)] + [(12, d) for d in (6, 24, 48)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n, d in runs:
            sets = [f'scheme.delassus="{args.delassus}"'] if args.delassus else []
            r = run_signorini(args.signorini, scene(n, args.steps, d), tmp, f'b{n}x{d}', sets)
            r['contacts'] = (n + 1) ** 2
            r['cells'] = [n, n, d]
            rows.append(r)
            print(json.dumps(r), flush=True)
    x = np.array([[1.0, np.log(r['dofs']), np.log(r['contacts'])] for r in rows])
    print("| quantity | exponent on dofs | exponent on contacts | largest residual (log) |")
    print("|---|---|---|---|")
    for key, name in [('setup_seconds', 'set-up'), ('seconds_per_step', 'time per step'),
                      ('peak_rss_mib', 'peak memory')]:
        y = np.log([r[key] for r in rows])
        coef, *_ = np.linalg.lstsq(x, y, rcond=None)
        res = np.max(np.abs(x @ coef - y))
        print(f"| {name} | {coef[1]:.2f} | {coef[2]:.2f} | {res:.2f} |")


def compare(args):
    """K pairs in turn (GetFEM, then signorini), medians and the per-step ratio."""
    import os
    import statistics
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        rows = {'getfem': [], 'signorini': []}
        for k in range(args.pairs):
            out = subprocess.run(
                [sys.executable, os.path.abspath(__file__), '--cells', str(args.cells),
                 '--steps', str(args.steps), '--lsolver', args.lsolver],
                check=True, capture_output=True, text=True).stdout
            g = json.loads([line for line in out.splitlines() if line.startswith('{')][-1])
            rows['getfem'].append(g)
            print(json.dumps(g), flush=True)
            r = run_signorini(args.signorini, scene(args.cells, args.steps), tmp, f'out{k}')
            r['cells_per_block'] = args.cells
            rows['signorini'].append(r)
            print(json.dumps(r), flush=True)
    med = {c: {key: statistics.median(x[key] for x in rs)
               for key in ['setup_seconds', 'seconds_per_step', 'peak_rss_mib']}
           for c, rs in rows.items()}
    gm = statistics.median(x['median_step_seconds'] for x in rows['getfem'])
    ratios = [g['seconds_per_step'] / s['seconds_per_step'] for g, s in zip(rows['getfem'], rows['signorini'])]
    ratios_med = [g['median_step_seconds'] / s['seconds_per_step'] for g, s in zip(rows['getfem'], rows['signorini'])]
    print(f"| {args.cells}^3 + {args.cells}^3 hex8, {args.steps} steps, {args.pairs} pairs (medians) | GetFEM | signorini |")
    print("|---|---|---|")
    print(f"| set-up | {med['getfem']['setup_seconds']:.2f} s | {med['signorini']['setup_seconds']:.2f} s |")
    print(f"| time per step (mean over the run) | {med['getfem']['seconds_per_step']:.3f} s (median step {gm:.3f} s) "
          f"| {med['signorini']['seconds_per_step']:.3f} s |")
    print(f"| peak memory | {med['getfem']['peak_rss_mib']:.0f} MiB | {med['signorini']['peak_rss_mib']:.0f} MiB |")
    print(f"GetFEM / signorini per step: median {statistics.median(ratios):.1f} "
          f"(range {min(ratios):.1f}-{max(ratios):.1f}); against GetFEM's median step "
          f"{statistics.median(ratios_med):.1f} (range {min(ratios_med):.1f}-{max(ratios_med):.1f})")


if __name__ == '__main__':
    main()
