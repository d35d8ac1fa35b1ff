"""
One PlanSequence request against one snapshot: the ROS-level checks, then the core.

This is the service's logic without the ROS graph: the node calls it with a
snapshot of its subscriptions and parameters, ``punctured-planner plan`` calls
it offline with a parameter file. :meth:`PlanSequenceHandler.handle` runs
named steps that return values, as nav2's computePlan: gather and check
(:mod:`punctured_planner.ros.checks`, codes 1-8 in priority order), plan (the
core: codes 9-13) and answer (paths and response; codes 3 and 4 where the plan
has more poses than max_poses or stamps past 2038). Every PlanningError they
raise is worded (:mod:`punctured_planner.ros.wording`) and becomes the
response's error code in one place, :meth:`PlanSequenceHandler.handle`.
"""

from collections import OrderedDict
import functools
import threading
import time
from typing import Any

import numpy as np

from . import checks
from . import conversions
from .parameters import InvalidParameter
from .settings import PlannerSettings
from .snapshot import ObstacleSet
from .snapshot import Outcome
from .snapshot import Snapshot
from .wording import ObstacleNames
from .wording import RequestNames
from .. import core
from ..core import ErrorCode
from ..core import PlanningError
from ..core import Workspace
from ..core.errors import counted

# Workspaces kept (one per obstacle set and options): a few, for topics that alternate.
WORKSPACE_CACHE_SIZE = 4


def refuse_stopping(response: Any, node_name: str, number: int, configuration_count: int,
                    into_stop: float) -> None:
    """
    Fill response with NODE_STOPPING: request #number was taken into_stop s into a stop.

    Past the stop's planning budget, or while only its replies go out (the
    linger), a request is answered unplanned at once, so that the stop still
    answers every caller within its timeout (doc/design.md section 16).
    """
    conversions.fill_error(
        response, ErrorCode.NODE_STOPPING,
        '%s stopping: request #%d (%s) was taken %.1f s after the stop signal, when the '
        'node no longer plans; send it again to a running node'
        % (node_name, number, counted(configuration_count, 'configuration'), into_stop))


# The Workspace option a core refusal names, as the node's parameter that sets it (the
# others share their names).
_PARAMETER_OF_OPTION = {'bounds': 'workspace_bounds'}


class PlanSequenceHandler:
    """Answers PlanSequence requests; keeps the last few Workspaces (one per obstacle set)."""

    def __init__(self) -> None:
        """Create an empty workspace cache."""
        self._cache: OrderedDict = OrderedDict()
        self._lock = threading.Lock()

    def workspace(self, settings: PlannerSettings, obstacles: np.ndarray) -> Workspace:
        """
        Return the Workspace for planar/3-D obstacles (r, d) and the settings (cached).

        The frame is fixed per obstacle set and options, so equal obstacle sets
        give the same Workspace object (and the same domains). Raises PlanningError.
        """
        obstacles = np.ascontiguousarray(obstacles, dtype=float)
        key = (obstacles.shape, obstacles.tobytes(), settings.dimension, settings.core_variant,
               settings.lane_spacing, settings.min_spacing, settings.required_clearance,
               settings.robot_radius, settings.obstacle_radius, settings.workspace_bounds)
        with self._lock:
            found = self._cache.get(key)
            if found is not None:
                self._cache.move_to_end(key)
                return found
        workspace = Workspace(obstacles, dimension=settings.dimension,
                              lane_spacing=settings.lane_spacing,
                              variant=settings.core_variant, min_spacing=settings.min_spacing,
                              required_clearance=settings.required_clearance,
                              robot_radius=settings.robot_radius,
                              # no obstacles, no radius to fit: per-obstacle radii wait
                              # for a set
                              obstacle_radius=(settings.core_obstacle_radius if len(obstacles)
                                               else 0.0),
                              bounds=settings.core_bounds)
        with self._lock:
            self._cache[key] = workspace
            while len(self._cache) > WORKSPACE_CACHE_SIZE:
                self._cache.popitem(last=False)
        return workspace

    def handle(self, request: Any, response: Any, snapshot: Snapshot,
               now_ns: int) -> Outcome:
        """
        Answer ``request`` against ``snapshot``; return an Outcome (never raises).

        now_ns is the request time; the paths start at now_ns + planning time.
        Unexpected exceptions become error_code UNKNOWN with their message (and
        are kept in Outcome.exception for the log).
        """
        started = time.perf_counter()
        gathered = checked = None
        try:
            gathered = checks.gather(request, snapshot, now_ns)
            checked = checks.check(gathered, snapshot)
            the_plan = self._plan(checked, snapshot)
            return self._answer(response, gathered, checked, the_plan, snapshot.settings,
                                now_ns, started)
        except PlanningError as error:
            # Before gathering ends, the request's own labels (the state first, with
            # use_current_state) all the same.
            label = (gathered.label if gathered is not None else functools.partial(
                checks.configuration_label, checks.requested_state(request, snapshot)))
            names = RequestNames(snapshot.obstacles.name, label,
                                 checked.planned if checked is not None else None,
                                 snapshot.settings.robot_names)
            conversions.fill_error(response, error.code, error.describe(names),
                                   time.perf_counter() - started, error.clearance, error.gap)
            return Outcome(response=response)
        except Exception as error:  # any bug becomes UNKNOWN, the node serves on
            conversions.fill_error(response, ErrorCode.UNKNOWN,
                                   'internal error: %s: %s' % (type(error).__name__, error),
                                   time.perf_counter() - started)
            return Outcome(response=response, exception=error)

    def check_obstacles(self, settings: PlannerSettings, obstacles: ObstacleSet) -> None:
        """
        Raise PlanningError if an obstacle set cannot be planned in.

        The node calls this when a set arrives, so a bad set is refused at once
        and the previous good set stays; requests run the same checks again.
        The node words the error with :class:`ObstacleNames`.
        """
        checks.check_obstacle_values(obstacles)
        checks.check_obstacle_frame(settings, obstacles)
        checks.check_obstacle_plane(settings, obstacles)
        checks.check_obstacle_range(settings, obstacles)
        self.check_workspace(settings, obstacles)

    def check_parameter_obstacles(self, settings: PlannerSettings, obstacles: ObstacleSet,
                                  changed: set[str]) -> None:
        """
        Raise ValueError, the culprit named, if settings cannot plan among these obstacles.

        For the node's on-set and start-up, and ``punctured-planner plan``'s parameter
        file: a new obstacles value (in changed) gets the checks a set arriving on the
        topic gets (check_obstacles); the set in use, from the parameter or from the
        topic, when other settings change, the core's Workspace rule (check_workspace:
        its obstacle_radius count, obstacles beyond workspace_bounds), so no change is
        taken that would refuse every request. So plane_z or frame_id may change first
        and the obstacles follow.
        """
        try:
            (self.check_obstacles if 'obstacles' in changed
             else self.check_workspace)(settings, obstacles)
        except PlanningError as error:
            # One of the two changed alone, and their counts no longer fit: a set of
            # parameters (ros2 param set, ros2 param load) applies one at a time.
            hint = ('; to change obstacles and obstacle_radius together, set both '
                    'atomically (the set_parameters_atomically service) or make '
                    'obstacle_radius one value first'
                    if error.option == 'obstacle_radius'
                    and len(changed & {'obstacles', 'obstacle_radius'}) == 1 else '')
            # The parameters involved, those that changed first; the core's PlanningError
            # (code, obstacle, wall, option) stays as the cause.
            involved = {'obstacles'} if obstacles.from_parameter else set()
            if error.option is not None:  # the core's option is the parameter of its name
                involved.add(_PARAMETER_OF_OPTION.get(error.option, error.option))
            if error.wall is not None:
                involved.add('workspace_bounds')
            raise InvalidParameter(
                # the changed ones where the core names no parameter (a topic's set)
                tuple(sorted(involved & changed) + sorted(involved - changed))
                or tuple(sorted(changed)),
                '%s with %s: %s%s' % (error.code.name, obstacles.describe(),
                                      error.describe(ObstacleNames(obstacles.name)), hint)
            ) from error

    def check_workspace(self, settings: PlannerSettings, obstacles: ObstacleSet) -> None:
        """
        Raise PlanningError if the core refuses a workspace of these obstacles and settings.

        The core's Workspace rule alone (obstacle_radius per obstacle, coincident
        obstacles, obstacles beyond workspace_bounds), for a set already checked
        as it arrived (check_obstacles) whose settings change.
        """
        self.workspace(settings, conversions.leading_coordinates(obstacles.points,
                                                                 settings.dimension))

    def _plan(self, checked: checks.Checked, snapshot: Snapshot) -> core.Plan:
        """Step 3: the core's certified plan of the planned coordinates."""
        d = snapshot.settings.dimension
        workspace = self.workspace(snapshot.settings,
                                   conversions.leading_coordinates(snapshot.obstacles.points, d))
        return core.plan(workspace, conversions.leading_coordinates(checked.positions, d),
                         refine=snapshot.settings.refine)

    @staticmethod
    def _answer(response: Any, gathered: checks.Gathered, checked: checks.Checked,
                the_plan: core.Plan, settings: PlannerSettings, now_ns: int,
                started: float) -> Outcome:
        """Step 4: stamps, paths and the filled response; return the Outcome."""
        planning_time = time.perf_counter() - started
        start_ns = int(now_ns) + int(round(planning_time * 1e9))
        max_speed, max_acceleration = gathered.max_speed, settings.max_acceleration
        with np.errstate(over='ignore', divide='ignore', invalid='ignore'):
            duration = the_plan.duration(max_speed, max_acceleration)
            # The answer's own breakpoints: the refinement's knots add to any schedule's,
            # and a leg in which no robot moves adds none.
            breakpoints = the_plan.stamped_breakpoints(max_speed, max_acceleration)
        checks.check_poses(settings, gathered.counts[0], breakpoints, gathered.samples_per_leg)
        # what the motion lasts at max_speed alone (which limit a refusal names): only then
        checks.check_duration(duration, lambda: the_plan.duration(max_speed), max_speed,
                              max_acceleration, start_ns)
        samples = the_plan.sample(gathered.samples_per_leg, max_speed, max_acceleration)
        paths = conversions.plan_to_paths(samples, checked.orientations, settings.frame_id,
                                          start_ns, settings.plane_z)
        conversions.fill_response(response, the_plan, paths, planning_time, duration,
                                  samples.waypoints, checked.dropped)
        return Outcome(response=response, plan=the_plan, paths=paths,
                       names=conversions.robot_names(settings.robot_names, gathered.counts[0]),
                       start_ns=start_ns, max_speed=max_speed,
                       max_acceleration=max_acceleration)
