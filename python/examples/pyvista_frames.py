"""The ball drop's frames opened in pyvista in one call (`Simulation.frames()`), the
ball's lowest point read at each frame and the last frame rendered off screen with its
von Mises stress.

    pip install pyvista
    python examples/pyvista_frames.py [OUT]
"""

import os
import sys

import numpy as np
import pyvista

import signorini

MESHES = os.path.join(os.path.dirname(__file__), "..", "..", "meshes")


def main() -> None:
    out = sys.argv[1] if len(sys.argv) > 1 else "out/ball_drop_pyvista"
    scene = signorini.Scene.from_toml(os.path.join(MESHES, "ball_drop.toml"))
    sim = scene.simulation()
    sim.run(out=out, plots=False)
    frames = sim.frames()  # a pyvista reader of fields.pvd
    lowest = []
    for t in frames.time_values:
        frames.set_active_time_value(t)
        grid = frames.read()[0]
        z = grid.points[:, 2] + grid.point_data["displacement"][:, 2]
        lowest.append((t, float(z.min())))
    for t, z in lowest[:: max(1, len(lowest) // 10)]:
        print(f"t = {t:.4f} s: lowest point z = {z * 1e3:8.3f} mm")
    frames.set_active_time_value(frames.time_values[-1])
    grid = frames.read()[0]
    shown = grid.warp_by_vector("displacement")
    plotter = pyvista.Plotter(off_screen=True)
    plotter.add_mesh(shown, scalars="von_mises", cmap="viridis")
    png = os.path.join(out, "last_frame.png")
    plotter.screenshot(png)
    print(f"{len(lowest)} frames read; the last one rendered to {png}")
    floor = scene.to_dict()["obstacles"][0]["point"][2]
    print(
        f"lowest point over the run: {min(z for _, z in lowest) * 1e3:.3f} mm "
        f"(the floor is at {floor * 1e3:.3f} mm)"
    )
    assert np.isfinite([z for _, z in lowest]).all()


if __name__ == "__main__":
    main()
