"""Ctrl-C latency of `Simulation.step(n)`: an interrupt from another thread 0.5 s into a
run of the scene given (e.g. meshes/hex_bars.toml), five times; prints the seconds
until KeyboardInterrupt (median and max)."""
import _thread, threading, time, sys
import signorini
scene = signorini.Scene.from_toml(sys.argv[1])
lat = []
for trial in range(5):
    sim = scene.simulation()
    sim.step(1)
    t = {}
    def fire():
        time.sleep(0.5)
        t["fired"] = time.perf_counter()
        _thread.interrupt_main()
    th = threading.Thread(target=fire); th.start()
    try:
        sim.step(sim.steps_total - 1)
        print("finished before the interrupt")
    except KeyboardInterrupt:
        lat.append(time.perf_counter() - t["fired"])
    th.join()
lat.sort()
print("latency s: median %.3f max %.3f over %d" % (lat[len(lat)//2], lat[-1], len(lat)), [round(x,3) for x in lat])
