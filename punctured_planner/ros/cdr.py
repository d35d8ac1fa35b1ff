"""
A plan's nav_msgs/Paths, and the same serialised with numpy as rmw_fastrtps writes them.

The planner publishes every robot's Path as these bytes (:class:`Paths`, built
once with the response's Paths by
:func:`punctured_planner.ros.conversions.plan_to_paths`); test_conversions
compares them with ``rclpy.serialization.serialize_message``.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

from nav_msgs.msg import Path
import numpy as np

# CDR as rmw_fastrtps writes it: encapsulation header (little endian), then the fields,
# each aligned to its size counted from the end of the header.
_CDR_HEADER = b'\x00\x01\x00\x00'


def _align(offset: int, size: int) -> int:
    return -(-offset // size) * size


def _stamped_pose_dtype(frame: bytes, start: int) -> np.dtype:
    """Return the numpy layout of a geometry_msgs/PoseStamped in frame ``frame`` at ``start``."""
    pose = _align(start + 13 + len(frame), 8) - start  # stamp, string (length, bytes, NUL)
    return np.dtype({'names': ['sec', 'nanosec', 'length', 'frame', 'pose'],
                     'formats': ['<i4', '<u4', '<u4', 'S%d' % (len(frame) + 1), ('<f8', 7)],
                     'offsets': [0, 4, 8, 12, pose], 'itemsize': pose + 56})


def serialized_paths(frame_id: str, start_ns: int, stamps: np.ndarray,
                     values: np.ndarray) -> list[bytes]:
    """
    Return nav_msgs/Paths serialised, built with numpy: one per row of values (k, M, 7).

    The bytes ``rclpy.serialization.serialize_message`` gives for the Paths of
    :func:`~punctured_planner.ros.conversions.plan_to_paths` (padding zeroed): header
    stamp start_ns, poses stamped ``stamps`` (M,) ns in frame_id, with positions and
    orientations ``values``.
    """
    frame = frame_id.encode()
    robots, count = values.shape[:2]
    first = _align(13 + len(frame), 4) + 4  # header, then the sequence length
    head = _stamped_pose_dtype(frame, first)
    rest = _stamped_pose_dtype(frame, 0)  # a pose ends 8-aligned: the rest repeat
    size = first + (head.itemsize + (count - 1) * rest.itemsize if count else 0)
    body = np.zeros((robots, size), dtype=np.uint8)
    stamp_sec, stamp_nanosec = divmod(int(start_ns), 1000000000)
    body[:, :12].view('<u4')[:] = (stamp_sec, stamp_nanosec, len(frame) + 1)
    body[:, 12:12 + len(frame)] = np.frombuffer(frame, dtype=np.uint8)
    body[:, first - 4:first].view('<u4')[:] = count
    for dtype, start, select in ((head, first, slice(0, 1)),
                                 (rest, first + head.itemsize, slice(1, None))):
        elements = np.zeros((robots, len(stamps[select])), dtype=dtype)
        elements['sec'], elements['nanosec'] = divmod(stamps[select], 1000000000)
        elements['length'] = len(frame) + 1
        elements['frame'] = frame
        elements['pose'] = values[:, select]
        body[:, start:start + elements.shape[1] * dtype.itemsize] = elements.view(
            np.uint8).reshape(robots, -1)
    return [_CDR_HEADER + row.tobytes() for row in body]


@dataclass(frozen=True)
class PathValues:
    """The values of a plan's Paths as arrays: what their CDR bytes are built from."""

    frame_id: str
    start_ns: int            # the stamp of the first pose
    stamps: np.ndarray       # (M,) ns, one per pose
    xyz: np.ndarray          # (k, M, 3) positions
    quaternions: np.ndarray  # (k, n, 4) orientations at the waypoints
    held: np.ndarray         # (M,) pose i holds quaternions[:, held[i]]


class Paths(list):
    """
    The robots' nav_msgs/Paths, and ``serialized``: the same Paths as CDR bytes (topics).

    The bytes are built on first use: only the topics need them, and the node
    publishes after the reply (msg_docs/topics.md), so the reply does not wait for them.
    """

    def __init__(self, paths: Iterable[Path], values: PathValues) -> None:
        """Keep the Paths and the values their bytes are built from."""
        super().__init__(paths)
        self.values = values

    @cached_property
    def serialized(self) -> list[bytes]:
        """Return each Path as CDR bytes (:func:`serialized_paths`)."""
        values = self.values
        return serialized_paths(values.frame_id, values.start_ns, values.stamps,
                                np.concatenate([values.xyz, values.quaternions[:, values.held]],
                                               axis=-1))
