"""display.py: a headless LinuxCNC display for tests/plan/lcnc_reference.py. Homes the machine, runs the program
named in prog.txt (beside this file) once, and writes "SECONDS (x, y, z) ERROR" to result.txt: the wall time from
AUTO_RUN until the interpreter is idle and the motion queue empty. LinuxCNC passes a display no environment of
ours, so everything comes through files."""
import linuxcnc, time, os
here = os.path.dirname(os.path.abspath(__file__))
prog = open(os.path.join(here, 'prog.txt')).read().strip()
out = os.path.join(here, 'result.txt')
s = linuxcnc.stat(); c = linuxcnc.command(); e = linuxcnc.error_channel()
def wait(cond, t=30):
    t0 = time.time()
    while time.time() - t0 < t:
        s.poll()
        if cond(): return True
        time.sleep(0.002)
    return False
try:
    c.state(linuxcnc.STATE_ESTOP_RESET); c.state(linuxcnc.STATE_ON)
    wait(lambda: s.task_state == linuxcnc.STATE_ON)
    c.mode(linuxcnc.MODE_MANUAL); c.wait_complete()
    c.teleop_enable(0); c.wait_complete()
    c.home(-1); c.wait_complete()
    wait(lambda: all(s.homed[i] for i in range(3)), 60)
    c.teleop_enable(1); c.wait_complete()
    c.mode(linuxcnc.MODE_AUTO); c.wait_complete()
    c.program_open(prog); c.wait_complete()
    time.sleep(0.5)
    t0 = time.monotonic()
    c.auto(linuxcnc.AUTO_RUN, 0)
    wait(lambda: s.interp_state != linuxcnc.INTERP_IDLE, 2)
    wait(lambda: s.interp_state == linuxcnc.INTERP_IDLE and s.queue == 0, 36000)
    t = time.monotonic() - t0
    err = e.poll()
    open(out, 'w').write(f"{t:.4f} {s.position[:3]} {err}\n")
except Exception as ex:
    open(out, 'w').write(f"error {ex}\n")
finally:
    c.state(linuxcnc.STATE_ESTOP)
    os.system('linuxcnc -k 2>/dev/null || true')
