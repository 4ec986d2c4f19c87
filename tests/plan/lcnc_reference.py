#!/usr/bin/env python3
"""lcnc_reference.py: the LinuxCNC reference cycle times of tests/plan/programs/*.ngc (docs/plan.md, "The
LinuxCNC reference").

Runs LinuxCNC's simulator (linuxcnc-uspace: its real motion controller and trajectory planner, in real time,
headless) on each program, three times, on a configuration derived from the installed sample
sim/axis/axis_mm.ini, and writes tests/plan/lcnc_times.json: the limits read back from the generated INI, and
per program the median of the measured seconds from AUTO_RUN to the end of motion (and every run). The program
baseline.ngc (a 2 mm move) measures the fixed cost of a run (reading the program, queueing, the display's
polling), which test_plan_reference subtracts from the others.

    as root (rtapi_app then needs RTAPI_UID, set here to nobody's uid):
    python3 tests/plan/lcnc_reference.py [--repeat N] [--timeout S] [--table T.json] [PROGRAM.ngc ...]

Each run takes the program's machine time plus a restart of LinuxCNC (all eleven programs, three runs each: about
eight minutes). CI does not run this: the table is committed, and test_plan_reference
(tests/plan/test_plan_reference.c) compares frepmill's planner with it."""
import argparse, configparser, json, os, shutil, statistics, subprocess, sys, tempfile, time

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLE = '/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis'


def make_config(d):
    """A headless copy of the sample sim configuration: our display, no Tk tool change dialog."""
    shutil.copy(os.path.join(HERE, 'lcnc', 'display.py'), d)
    shutil.copy(os.path.join(SAMPLE, 'sim_mm.tbl'), d)
    open(os.path.join(d, 'sim_mm.var'), 'w').close()
    open(os.path.join(d, 'empty.hal'), 'w').close()
    with open(os.path.join(d, 'display.sh'), 'w') as f:
        f.write('#!/bin/sh\nexec /usr/bin/python3 %s/display.py "$@" > %s/display.log 2>&1\n' % (d, d))
    os.chmod(os.path.join(d, 'display.sh'), 0o755)
    out = []
    for line in open(os.path.join(SAMPLE, 'axis_mm.ini')):
        if line.startswith('DISPLAY = axis'):
            line = 'DISPLAY = %s/display.sh\n' % d
        elif line.startswith('HALFILE = axis_manualtoolchange.hal'):
            line = 'HALFILE = %s/empty.hal\n' % d
        elif line.startswith('POSTGUI_HALFILE'):
            line = '#' + line
        out.append(line)
    open(os.path.join(d, 'sim.ini'), 'w').write(''.join(out))
    subprocess.run(['chmod', '-R', 'a+rwX', d], check=True)


def limits(ini_path):
    """The dynamics the planner uses, from the generated INI (mm, s)."""
    ini = configparser.ConfigParser(strict=False, interpolation=None, inline_comment_prefixes=('#',))
    ini.optionxform = str
    ini.read(ini_path)
    g = lambda s, k: float(ini[s][k])
    return {'axes': {a.lower(): {'max_velocity': g('AXIS_' + a, 'MAX_VELOCITY'),
                                  'max_acceleration': g('AXIS_' + a, 'MAX_ACCELERATION')} for a in 'XYZ'},
            'traj': {'max_velocity': g('TRAJ', 'MAX_LINEAR_VELOCITY'),
                     'max_acceleration': g('TRAJ', 'MAX_LINEAR_ACCELERATION')},
            'servo_period_s': g('EMCMOT', 'SERVO_PERIOD') * 1e-9,
            'max_feed_override': g('DISPLAY', 'MAX_FEED_OVERRIDE')}


def run(d, prog, timeout):
    p = os.path.join(d, os.path.basename(prog))
    shutil.copy(prog, p)
    os.chmod(p, 0o644)
    open(os.path.join(d, 'prog.txt'), 'w').write(p + '\n')
    res = os.path.join(d, 'result.txt')
    if os.path.exists(res):
        os.remove(res)
    env = dict(os.environ, RTAPI_UID=os.environ.get('RTAPI_UID', '65534'),
               RTAPI_FIFO_PATH=os.path.join(d, '.rtapi_fifo'))
    subprocess.run(['linuxcnc', os.path.join(d, 'sim.ini')], env=env, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, timeout=timeout)
    text = open(res).read().split()
    if text[0] == 'error' or text[-1] != 'None':
        raise RuntimeError('%s: %s' % (prog, ' '.join(text)))
    return float(text[0])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--repeat', type=int, default=3, help='runs per program; the table keeps the median')
    ap.add_argument('--timeout', type=float, default=120, help='seconds a run may take: the machine time plus about 10 s')
    ap.add_argument('--table', default=os.path.join(HERE, 'lcnc_times.json'), help='the table to update')
    ap.add_argument('programs', nargs='*')
    a = ap.parse_args()
    progs = a.programs or sorted(os.path.join(HERE, 'programs', p)
                                 for p in os.listdir(os.path.join(HERE, 'programs')) if p.endswith('.ngc'))
    table_path = a.table
    table = json.load(open(table_path)) if os.path.exists(table_path) else {}
    d = tempfile.mkdtemp(prefix='lcnc-ref-')
    os.chmod(d, 0o777)
    make_config(d)
    version = subprocess.run(['dpkg-query', '-W', '-f', '${Version}', 'linuxcnc-uspace'],
                             capture_output=True, text=True).stdout
    table['linuxcnc'] = 'linuxcnc-uspace ' + version
    table['config'] = 'sample sim/axis/axis_mm.ini, headless (tests/plan/lcnc_reference.py)'
    table['limits'] = limits(os.path.join(d, 'sim.ini'))
    times = table.setdefault('seconds', {})
    runs_table = table.setdefault('runs', {})
    table['recorded'] = time.strftime('%Y-%m-%d')
    for prog in progs:
        runs = []
        for _ in range(a.repeat):
            try:
                runs.append(run(d, prog, a.timeout))
            except (RuntimeError, subprocess.TimeoutExpired) as ex:
                # a run that hangs (rarely, the display never connects) is retried once
                print('%s: %s, once more' % (os.path.basename(prog), ex), flush=True)
                subprocess.run(['linuxcnc', '-k'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                runs.append(run(d, prog, a.timeout))
        name = os.path.basename(prog)
        # the median: on a loaded machine a run can be delayed (a late servo thread) and the
        # display's polling has been seen to stop one early; the middle of three is neither
        times[name] = statistics.median(runs)
        runs_table[name] = runs
        print('%-20s %s' % (name, ' '.join('%.4f' % r for r in runs)), flush=True)
        json.dump(table, open(table_path, 'w'), indent=1, sort_keys=True)
        open(table_path, 'a').write('\n')
    shutil.rmtree(d, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
