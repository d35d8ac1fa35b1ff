"""
From plan to motion, measured: 20 disc robots, a slow one, a late one, noise.

``make bench`` runs this after the planner benchmarks (``.venv/bin/python
bench/execution.py [--quick]``) and writes bench/execution.md. Two parts:

1. Without DDS (punctured_planner.execution against punctured_planner.sim):
   every other robot in turn is the slow one (speed factor 0.5) and the next
   one the late one (200 ms command latency), 5% velocity noise, with the
   shared clock and without it (each robot following the stamps on its own).
2. Over DDS: fleet_sim and plan_executor as processes, the plan published on
   ``plan`` as planner_node publishes it (conversions.plan_message), the goal
   sent through the ExecutePlan action: with the shared clock, without it,
   then a run with a robot's odometry muted for 2 s and a cancel; then the same
   plan with the same faults on differential-drive robots (1.9 rad/s, 1 m/s^2,
   8 rad/s^2), every cmd_vel checked for a zero linear.y (``--drives``: only the
   two shared-clock runs, holonomic and differential, printed).

The plan comes from the core with robot_radius 0.1 m (discs variant, refined, with
required_clearance 0.3 m so that the tracking tolerance, half the plan's min_gap, leaves
room for the late robot), in a 12 m x 14 m hall with 3 pillars; its min_gap is the
exact surface gap.
"""

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
from punctured_planner.ros.client import spin_until
from punctured_planner.ros.conversions import duration_to_seconds

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS_MD = os.path.join(HERE, 'execution.md')
K = 20
RADIUS = 0.1
SPEED = 0.5          # the robots' speed limit and the plan's max_speed (m/s)
ACCELERATION = 1.0   # the robots' acceleration limit and the plan's max_acceleration (m/s^2)
LATENCY = 0.2
NOISE = 0.05
CLEARANCE = 0.3  # the plan's required gap (m): room to track at half of it
OBSTACLES = np.array([[-3.0, 0.4], [0.2, -0.3], [3.1, 0.2]])


def configurations(seed=12):
    """Return (2, K, 2): K robots at least 1 m apart above the pillars, then below them."""
    rng = np.random.default_rng(seed)
    result = []
    for low, high in (([-6, 1.5], [6, 7]), ([-6, -7], [6, -1.5])):
        points = []
        while len(points) < K:
            q = rng.uniform(low, high)
            if all(np.hypot(*(q - p)) > 1.0 for p in points):
                points.append(q)
        result.append(points)
    return np.array(result)


def core_plan():
    """Return the certified core plan of the scenario (bodies of radius RADIUS)."""
    from punctured_planner.core import plan
    from punctured_planner.core import Workspace
    workspace = Workspace(OBSTACLES, variant='discs', min_spacing=0.6, robot_radius=RADIUS,
                          required_clearance=CLEARANCE)
    return plan(workspace, configurations())


def xyz(points):
    """Return (..., 2) points as (..., 3) with z = 0."""
    return np.concatenate([points, np.zeros(points.shape[:-1] + (1,))], axis=-1)


# ---------------------------------------------------------------- part 1: no DDS

def simulate(the_plan, slow, late, shared_clock, **settings):
    """
    Run Execution at 20 Hz against a Fleet at 40 Hz; return a dict of figures.

    settings are further ExecutionSettings fields (bench/feedforward.py's values).
    """
    from punctured_planner.execution import Bodies
    from punctured_planner.execution import Execution
    from punctured_planner.execution import ExecutionSettings
    from punctured_planner.execution import Reference
    from punctured_planner.sim import Fleet
    from punctured_planner.sim import FleetSettings
    positions = xyz(the_plan.positions)
    reference = Reference.timed(the_plan.stamps(SPEED, ACCELERATION), positions,
                                np.tile([0.0, 0.0, 0.0, 1.0], positions.shape[:2] + (1,)),
                                SPEED, ACCELERATION, the_plan.tracking_tolerance)
    bodies = Bodies(RADIUS, xyz(OBSTACLES), np.zeros(len(OBSTACLES)))
    tolerance = the_plan.tracking_tolerance
    fleet = Fleet(positions[0], FleetSettings(
        bodies=bodies, speed_limit=SPEED, speed_factors=speed_factors(slow),
        latencies=np.where(np.arange(K) == late, LATENCY, 0.0), velocity_noise=NOISE,
        seed=slow, max_acceleration=ACCELERATION))
    execution = Execution(reference, tolerance, ExecutionSettings(
        speed_limit=SPEED, shared_clock=shared_clock, **settings), bodies)
    now, contacts = 0.0, 0
    while now < 10 * reference.duration:
        step = execution.step(0.05, fleet.positions, np.zeros(K, dtype=bool))
        for robot in range(K):
            fleet.command(robot, step.velocities[robot], now)
        for _ in range(2):
            contacts += len(fleet.step(now, 0.025))
            now += 0.025
        if step.finished:
            break
    return {'gap': fleet.min_gap, 'contacts': contacts, 'seconds': now,
            'error': execution.max_errors.max() / tolerance,
            'final': np.linalg.norm(fleet.positions - positions[-1], axis=1).max()}


def sweep(the_plan, quick):
    """Return rows (slow, late, shared figures, unshared figures) over the slow robot."""
    rows = []
    for slow in range(0, K, 10 if quick else 2):
        late = (slow + 1) % K
        rows.append((slow, late, simulate(the_plan, slow, late, True),
                     simulate(the_plan, slow, late, False)))
    return rows


# ---------------------------------------------------------------- part 2: DDS

class Graph:
    """fleet_sim and plan_executor processes, and this process's client node."""

    def __init__(self, the_plan, slow, late, shared_clock, tag, drive='holonomic'):
        """Start both processes in a fresh namespace and connect a client to them."""
        import rclpy
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from punctured_planner.ros.qos import LATCHED
        from punctured_planner_interfaces.action import ExecutePlan
        from punctured_planner_interfaces.msg import Plan
        from rclpy.action import ActionClient
        from rclpy.executors import SingleThreadedExecutor
        from std_msgs.msg import Float64
        self.names = ['robot_%d' % i for i in range(K)]
        self.namespace = '/pp_exec_%s_%d' % (tag, os.getpid())
        start = xyz(the_plan.configurations[0])
        params = tempfile.NamedTemporaryFile('w', suffix='.yaml', delete=False)
        params.write(PARAMETERS % {
            'names': self.names, 'start': start.ravel().tolist(),
            'factors': speed_factors(slow).tolist(),
            'latencies': np.where(np.arange(K) == late, LATENCY, 0.0).tolist(),
            'obstacles': xyz(OBSTACLES).ravel().tolist(),
            'clock': 'on' if shared_clock else 'off', 'drive': drive,
            'acceleration': ACCELERATION})
        params.close()
        self.logs = {}
        self.processes = {}
        for name in ('fleet_sim', 'plan_executor'):
            log = tempfile.NamedTemporaryFile(prefix='%s_' % name, suffix='.log', delete=False)
            self.logs[name] = log.name
            self.processes[name] = subprocess.Popen(
                [os.path.join(os.path.dirname(sys.executable), name), '--ros-args', '-r',
                 '__ns:=' + self.namespace, '--params-file', params.name],
                stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, args=[])
        self.node = rclpy.create_node('execution_bench', context=self.context,
                                      namespace=self.namespace)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.odometry = {}
        self.commands = {name: [] for name in self.names}
        self.gap = []
        for name in self.names:
            self.node.create_subscription(
                Odometry, name + '/odom',
                lambda msg, name=name: self.odometry.setdefault(name, []).append(
                    (time.monotonic(), msg)), 50)
            self.node.create_subscription(
                Twist, name + '/cmd_vel', lambda msg, name=name: self.commands[name].append(
                    (time.monotonic(), msg)), 50)
        self.node.create_subscription(Float64, 'fleet_sim/min_gap',
                                      lambda msg: self.gap.append(msg.data), LATCHED)
        self.plan_publisher = self.node.create_publisher(Plan, 'plan', LATCHED)
        self.action = ActionClient(self.node, ExecutePlan, 'execute_plan')
        self.sim_parameters = None

    def spin(self, predicate, timeout_sec):
        """Spin until predicate() (or the timeout); return whether it became true."""
        return spin_until(self.executor, predicate, timeout_sec)

    def publish_plan(self, the_plan, plan_id):
        """Publish the plan as planner_node would (conversions.plan_message)."""
        from punctured_planner.ros import conversions
        from punctured_planner.ros.settings import PlannerSettings
        from punctured_planner.ros.snapshot import Outcome
        n = len(the_plan.configurations)
        start_ns = self.node.get_clock().now().nanoseconds
        paths = conversions.plan_to_paths(the_plan.sample(0, SPEED, ACCELERATION),
                                          np.tile([0.0, 0.0, 0.0, 1.0], (n, K, 1)), 'map',
                                          start_ns)
        outcome = Outcome(response=None, plan=the_plan, paths=paths, names=self.names,
                          start_ns=start_ns, max_speed=SPEED, max_acceleration=ACCELERATION,
                          plan_id=plan_id)
        self.plan_publisher.publish(conversions.plan_message(outcome, PlannerSettings()))

    def execute(self, plan_id, during=None):
        """Send a goal, spin (calling during(feedback) each time); return (result, feedback)."""
        from punctured_planner_interfaces.action import ExecutePlan
        assert self.action.wait_for_server(timeout_sec=30), self.log('plan_executor')
        assert self.spin(lambda: len(self.odometry) == K, 30), 'no odometry'
        assert self.spin(lambda: self.plan_publisher.get_subscription_count() > 0, 30)
        assert self.spin(lambda: 'plan %d:' % plan_id in self.log('plan_executor'), 30)
        feedback = []
        future = self.action.send_goal_async(
            ExecutePlan.Goal(plan_id=plan_id),
            feedback_callback=lambda msg: feedback.append((time.monotonic(), msg.feedback)))
        assert self.spin(future.done, 10)
        handle = future.result()
        result = handle.get_result_async()
        while not result.done():
            self.executor.spin_once(timeout_sec=0.05)
            if during is not None and feedback:
                during(handle, feedback)
        return result.result().result, feedback

    def set_sim(self, **values):
        """Set fleet_sim parameters at run time."""
        from rclpy.parameter import Parameter
        from rclpy.parameter_client import AsyncParameterClient
        if self.sim_parameters is None:
            self.sim_parameters = AsyncParameterClient(self.node, 'fleet_sim')
            assert self.sim_parameters.wait_for_services(timeout_sec=10)
        future = self.sim_parameters.set_parameters(
            [Parameter(name, value=value) for name, value in values.items()])
        assert self.spin(future.done, 10)

    def positions(self):
        """Return every robot's last odometry position (K, 3)."""
        return np.array([[m.pose.pose.position.x, m.pose.pose.position.y,
                          m.pose.pose.position.z] for m in
                         (self.odometry[name][-1][1] for name in self.names)])

    def log(self, name):
        """Return a process's output so far."""
        with open(self.logs[name], encoding='utf-8', errors='replace') as stream:
            return stream.read()

    def close(self):
        """Ctrl-C both processes; return {name: (exit code, traceback seen, contacts)}."""
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        outcome = {}
        for name, process in self.processes.items():
            process.send_signal(signal.SIGINT)
            try:
                code = process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()
                code = 'killed'
            text = self.log(name)
            outcome[name] = (code, 'Traceback' in text, text.count('contact at'))
        return outcome


PARAMETERS = """
/**:
  ros__parameters:
    frame_id: map
/**/fleet_sim:
  ros__parameters:
    robot_names: %(names)s
    initial_positions: %(start)s
    robot_radius: 0.1
    obstacles: %(obstacles)s
    speed_limit: 0.5
    speed_factors: %(factors)s
    latencies: %(latencies)s
    velocity_noise: 0.05
    rate: 20.0
    drive: [%(drive)s]
    yaw_rate_limit: 1.9
    max_acceleration: [%(acceleration)s]
    max_yaw_acceleration: 8.0
/**/plan_executor:
  ros__parameters:
    speed_limit: 0.5
    control_rate: 20.0
    shared_clock: '%(clock)s'
    drive: [%(drive)s]
    yaw_rate_limit: 1.9
"""


def dds_run(the_plan, slow, late, shared_clock, tag, drive='holonomic'):
    """One full execution over DDS; return a dict of figures."""
    graph = Graph(the_plan, slow, late, shared_clock, tag, drive)
    try:
        graph.publish_plan(the_plan, 1)
        started = time.monotonic()
        result, feedback = graph.execute(1)
        wall = time.monotonic() - started
        assert result.error_code == 0, result.error_msg
        graph.spin(lambda: False, 0.5)
        final = np.linalg.norm(graph.positions() - xyz(the_plan.configurations[-1]),
                               axis=1).max()
        # the plan's orientations are the identity: every robot is asked to face +x
        headings = [abs(2 * np.arctan2(m.pose.pose.orientation.z, m.pose.pose.orientation.w))
                    for m in (graph.odometry[name][-1][1] for name in graph.names)]
        commands = [m for name in graph.names for _, m in graph.commands[name]]
        # the largest error while the clock ran: the last feedback before the plan's end
        running = [f for _, f in feedback if f.plan_time < f.plan_duration]
        figures = {'code': result.error_code, 'message': result.error_msg,
                   'executed': duration_to_seconds(result.executed_duration), 'wall': wall,
                   'error': max(result.max_tracking_errors), 'gap': graph.gap[-1],
                   'worst': int(np.argmax(result.max_tracking_errors)),
                   'running': max(running[-1].max_tracking_errors) if running else 0.0,
                   'final': final, 'feedback': len(feedback),
                   'heading': max((h + np.pi) % (2 * np.pi) - np.pi for h in headings),
                   'commands': len(commands),
                   'sideways': sum(1 for m in commands if m.linear.y != 0.0)}
    finally:
        figures_close = graph.close()
    figures['processes'] = figures_close
    return figures


def stale_and_cancel(the_plan, slow, late):
    """Mute a robot for 2 s mid-run, let it resume, then cancel; return the figures."""
    graph = Graph(the_plan, slow, late, True, 'cancel')
    marks = {}
    muted = graph.names[5]

    def during(handle, feedback):
        now, last = feedback[-1]
        if 'mute' not in marks and last.plan_time > 5.0:
            graph.set_sim(muted_robots=[muted])
            marks['mute'] = now
        elif 'mute' in marks and 'unmute' not in marks and now - marks['mute'] > 2.0:
            held = [f.plan_time for t, f in feedback if t > marks['mute'] + 0.6]
            marks['held'] = (max(held) - min(held), [f.stale_robots for t, f in feedback
                                                     if t > marks['mute'] + 0.6][-1])
            graph.set_sim(muted_robots=[])
            marks['unmute'] = time.monotonic()
            marks['plan_time'] = last.plan_time
        elif 'unmute' in marks and 'resumed' not in marks and \
                last.plan_time > marks['plan_time'] + 1e-6:
            marks['resumed'] = now - marks['unmute']
        elif 'resumed' in marks and 'cancel' not in marks and now - marks['unmute'] > 3.0:
            marks['cancel'] = time.monotonic()
            handle.cancel_goal_async()

    try:
        graph.publish_plan(the_plan, 1)
        result, _ = graph.execute(1, during)
        graph.spin(lambda: False, 1.0)
        asked = marks['cancel']
        zero_command = max(next(t for t, m in graph.commands[name] if t >= asked
                                and m.linear.x == m.linear.y == 0.0) for name in graph.names)

        def stopped(name):
            return next(t for t, m in graph.odometry[name] if t >= asked
                        and m.twist.twist.linear.x == m.twist.twist.linear.y == 0.0)

        stops = {name: stopped(name) - asked for name in graph.names}
        figures = {'code': result.error_code, 'held': marks['held'], 'resumed': marks['resumed'],
                   'muted': muted, 'zero_command': zero_command - asked,
                   'stop_others': max(v for n, v in stops.items() if n != graph.names[late]),
                   'stop_late': stops[graph.names[late]], 'gap': graph.gap[-1]}
    finally:
        figures_close = graph.close()
    figures['processes'] = figures_close
    return figures


# ---------------------------------------------------------------- report

def report(the_plan, rows, slow, late, shared, unshared, cancel, differential):
    """Return the Markdown of bench/execution.md."""
    nominal = the_plan.duration(SPEED, ACCELERATION)
    at_slow = the_plan.duration(SPEED * 0.5, ACCELERATION)
    tolerance = the_plan.tracking_tolerance
    bound = straight_bound(the_plan, slow)
    fleet_bound = float(straight_times(the_plan, slow).max())
    lines = [
        '# From plan to motion: execution figures',
        '',
        'Produced by `make bench` (`.venv/bin/python bench/execution.py`). %d disc robots '
        '(R = %.2f m) in a 12 m x 14 m hall with 3 pillars, one configuration above them to '
        'one below, discs variant with required_clearance %.2f m: plan duration %.1f s at '
        '%.1f m/s and %.1f m/s^2 (%.1f s '
        "at the slow robot's speed; %.1f s without the acceleration limit), min_gap %.3f m, "
        'tracking tolerance %.3f m. Speed limit %.1f m/s and acceleration limit %.1f m/s^2 '
        'for every robot, one robot at speed factor 0.5, the next with %d ms command '
        'latency, %d%% velocity noise.' % (
            K, RADIUS, CLEARANCE, nominal, SPEED, ACCELERATION, at_slow, the_plan.duration(SPEED),
            the_plan.min_gap, tolerance, SPEED, ACCELERATION, LATENCY * 1000, NOISE * 100),
        '',
        '## Over DDS (fleet_sim and plan_executor processes, ExecutePlan action)',
        '',
        'Slow robot robot_%d, late robot robot_%d. Shared clock: executed %.1f s = %.2fx '
        "the slow robot's straight-line bound (%.1f s at %.2f m/s), %.2fx the fleet's (%.1f s), "
        '%.2fx the plan at its speed (%.1f s), %.2fx the plan (%.1f s).' % (
            slow, late, shared['executed'], shared['executed'] / bound, bound, SPEED * 0.5,
            shared['executed'] / fleet_bound, fleet_bound,
            shared['executed'] / at_slow, at_slow, shared['executed'] / nominal, nominal),
        '',
        '| run | result | true smallest gap | contacts | executed / plan at slow speed | '
        'largest error / tolerance | farthest from last configuration | exits |',
        '|---|---|---|---|---|---|---|---|',
    ]
    for label, f in (('shared clock', shared), ('each robot on its own stamps', unshared)):
        exits = ', '.join('%s %s%s' % (n, c, ' traceback' if tb else '')
                          for n, (c, tb, _) in f['processes'].items())
        lines.append('| %s | %d | %.3f m | %d | %.2f (%.1f s) | %.2f | %.4f m | %s |' % (
            label, f['code'], f['gap'], f['processes']['fleet_sim'][2],
            f['executed'] / at_slow, f['executed'], f['error'] / tolerance, f['final'], exits))
    lines += ['', differential_line(differential, shared, tolerance)]
    held, stale = cancel['held']
    lines += [
        '',
        'Stale odometry: %s muted for 2 s at plan time 5 s: the plan clock moved %.3g s while '
        'the feedback named %s stale; after the odometry returned the clock resumed within '
        '%.0f ms. Cancel 3 s later: zero velocity published to every robot within %.0f ms of '
        'the cancel request; every robot without latency stopped (odometry speed 0) within '
        '%.0f ms, the %d ms robot within %.0f ms. Result code %d (CANCELED = 5); true gap '
        '%.3f m; exits %s.' % (
            cancel['muted'], held, stale, cancel['resumed'] * 1000,
            cancel['zero_command'] * 1000, cancel['stop_others'] * 1000, LATENCY * 1000,
            cancel['stop_late'] * 1000, cancel['code'], cancel['gap'],
            ', '.join('%s %s%s' % (n, c, ' traceback' if tb else '')
                      for n, (c, tb, _) in cancel['processes'].items())),
        '',
        '## Without DDS: every other robot as the slow one',
        '',
        'punctured_planner.execution against punctured_planner.sim, control 20 Hz, '
        'simulation 40 Hz, the late robot the one after the slow one.',
        '',
        "The slow robot's bound is its straight-line time at its speed; the fleet's "
        "bound is the largest of every robot's straight-line time at its own speed, which "
        'no execution can beat.',
        '',
        '| slow, late | shared clock: gap / contacts / executed / plan at slow speed / '
        "error / tolerance | executed / slow robot's bound / fleet's bound | own stamps: "
        'gap / contacts / error / tolerance |',
        '|---|---|---|---|',
    ]
    for s, lt, a, b in rows:
        lines.append('| %d, %d | %.3f m / %d / %.2f / %.2f | %.2f / %.2f | %.3f m / %d / '
                     '%.1f |' % (
                         s, lt, a['gap'], a['contacts'], a['seconds'] / at_slow, a['error'],
                         a['seconds'] / straight_bound(the_plan, s),
                         a['seconds'] / straight_times(the_plan, s).max(), b['gap'],
                         b['contacts'], b['error']))
    touching = sum(1 for row in rows if row[3]['gap'] < 0)
    to_bound = [r[2]['seconds'] / straight_bound(the_plan, r[0]) for r in rows]
    lines += ['', 'Shared clock: smallest gap %.3f m over all %d runs, largest executed / '
              "plan at slow speed %.2f, executed / the slow robot's bound median %.2f "
              '(largest %.2f). Own stamps: contact in %d of %d runs.' % (
                  min(r[2]['gap'] for r in rows), len(rows),
                  max(r[2]['seconds'] for r in rows) / at_slow, np.median(to_bound),
                  max(to_bound), touching, len(rows)), '']
    return '\n'.join(lines)


def speed_factors(slow):
    """Return every robot's speed factor: 0.5 for the slow one, 1 for the others."""
    return np.where(np.arange(K) == slow, 0.5, 1.0)


def straight_times(the_plan, slow):
    """Return (K,): each robot's straight-line time from its start to its goal at its speed."""
    start, goal = the_plan.configurations[0], the_plan.configurations[-1]
    return np.linalg.norm(goal - start, axis=-1) / (SPEED * speed_factors(slow))


def straight_bound(the_plan, slow):
    """Return the slow robot's straight-line time from its start to its goal at its speed."""
    return float(straight_times(the_plan, slow)[slow])


def differential_line(differential, holonomic, tolerance):
    """Return the sentence on the differential robots' run against the holonomic one."""
    f = differential
    return (
        'Differential drive, same plan and faults, shared clock (1.9 rad/s, 1 m/s^2, '
        '8 rad/s^2): result %d, true smallest gap %.3f m, %d contacts, largest tracking '
        'error while the clock ran %.3f m = %.2f of the tolerance (%.3f m = %.2f over the '
        'whole run, by robot_%d, stops after the end included; holonomic %.3f m and %.3f m, '
        'by robot_%d), farthest from its goal %.4f m, largest final heading error %.4f rad, '
        'executed %.1f s = %.2f x the holonomic run (%.1f s); %d cmd_vel messages, %d with '
        'a non-zero linear.y.' % (
            f['code'], f['gap'], f['processes']['fleet_sim'][2], f['running'],
            f['running'] / tolerance, f['error'], f['error'] / tolerance, f['worst'],
            holonomic['running'], holonomic['error'], holonomic['worst'], f['final'],
            f['heading'], f['executed'], f['executed'] / holonomic['executed'],
            holonomic['executed'], f['commands'], f['sideways']))


def main(argv=None):
    """Run both parts, print and write bench/execution.md."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--quick', action='store_true', help='2 runs without DDS only')
    parser.add_argument('--drives', action='store_true',
                        help='only the shared-clock DDS runs, holonomic and differential')
    args = parser.parse_args(argv)
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + (os.getpid() + 30) % 101))
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_LOG_DIR', tempfile.mkdtemp(prefix='pp_execution_log_'))
    the_plan = core_plan()
    if args.drives:
        shared = dds_run(the_plan, 0, 1, True, 'shared')
        print('DDS shared clock:', shared, flush=True)
        differential = dds_run(the_plan, 0, 1, True, 'diff', 'differential')
        print('DDS differential:', differential, flush=True)
        print(differential_line(differential, shared,
                                the_plan.tracking_tolerance))
        return 0
    rows = sweep(the_plan, args.quick)
    for row in rows:
        print('slow %d late %d: shared %s | own stamps %s' % row, flush=True)
    if args.quick:
        return 0
    # the DDS runs use the first slow robot whose unshared run touched (else robot 0)
    slow, late = next(((s, lt) for s, lt, _, b in rows if b['gap'] < 0), (0, 1))
    shared = dds_run(the_plan, slow, late, True, 'shared')
    print('DDS shared clock:', shared, flush=True)
    unshared = dds_run(the_plan, slow, late, False, 'own')
    print('DDS own stamps:', unshared, flush=True)
    cancel = stale_and_cancel(the_plan, slow, late)
    print('DDS stale and cancel:', cancel, flush=True)
    differential = dds_run(the_plan, slow, late, True, 'diff', 'differential')
    print('DDS differential:', differential, flush=True)
    text = report(the_plan, rows, slow, late, shared, unshared, cancel, differential)
    with open(RESULTS_MD, 'w', encoding='utf-8') as stream:
        stream.write(text)
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
