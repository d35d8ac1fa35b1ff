"""One request against one snapshot (planning.PlanSequenceHandler), without DDS."""

import numpy as np
from planner_helpers import make_request
from planner_helpers import OBSTACLES
from punctured_planner import conversions
from punctured_planner.parameters import settings_from_values
from punctured_planner.planning import ObstacleSet
from punctured_planner.planning import PlanSequenceHandler
from punctured_planner.planning import Snapshot


def snapshot(**values):
    settings = settings_from_values(values)
    return Snapshot(settings, ObstacleSet(conversions.obstacles_from_parameter(
        settings.obstacles)))


def test_planner_caches_one_workspace_per_obstacle_set():
    from punctured_planner_interfaces.srv import PlanSequence
    planner = PlanSequenceHandler()
    base = snapshot(obstacles=[v for o in OBSTACLES for v in o])
    first = planner.workspace(base.settings, np.array(OBSTACLES)[:, :2])
    assert planner.workspace(base.settings, np.array(OBSTACLES)[:, :2]) is first
    paper = settings_from_values({'variant': 'paper'})
    assert planner.workspace(paper, np.array(OBSTACLES)[:, :2]) is not first
    outcome = planner.handle(make_request(), PlanSequence.Response(), base, 0)
    assert outcome.ok and outcome.names == ['robot_0', 'robot_1', 'robot_2', 'robot_3']
    assert outcome.start_ns > 0
    again = planner.handle(make_request(), PlanSequence.Response(), base, 0)
    assert again.plan.workspace is first


def test_over_limit_requests_are_refused_before_conversion(monkeypatch):
    """REQUEST_OVER_LIMITS from list lengths: no pose is converted, whatever the values."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request()
    huge = PoseArray()
    huge.poses = [Pose()] * 20001  # one shared Pose: cheap to build
    request.configurations = [huge, huge]
    converted = []
    monkeypatch.setattr(conversions, 'pose_array_positions', converted.append)
    outcome = PlanSequenceHandler().handle(request, PlanSequence.Response(), snapshot(), 0)
    assert outcome.response.error_code == PlanSequence.Response.REQUEST_OVER_LIMITS
    assert 'max_robots 10000' in outcome.response.error_msg
    assert converted == []


def test_array_holding_dataclasses_compare_by_identity():
    """Frame, ObstacleSet, RobotState, PlaneView: == and hash work (no numpy ValueError)."""
    from punctured_planner.core import Workspace
    from punctured_planner.planning import RobotState
    from punctured_planner.viz.geometry import PlaneView
    frame = Workspace(np.array(OBSTACLES)[:, :2]).frame
    items = [frame, ObstacleSet(np.zeros((2, 3))), RobotState(np.zeros((2, 3)), np.zeros((2, 4))),
             PlaneView(np.zeros(2), np.eye(2)[0], np.eye(2)[1], ('x', 'y'))]
    for item in items:
        twin = type(item)(*(getattr(item, name) for name in item.__dataclass_fields__))
        assert item == item and not item == twin and len({item, twin}) == 2
