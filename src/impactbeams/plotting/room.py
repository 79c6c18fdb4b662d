"""The room left on a figure for one more label: boxes and leader lines it must keep clear of.

All in display units (pixels), measured on the laid-out figure. A box is a row (x0, y0, x1,
y1); a leader line the segment (x0, y0, x1, y1) from a label to its point; a curve's segment
likewise (the drawn data a label or the legend must not cover; a leader line starts on a curve,
so it may cross them). Touching counts as meeting (as `matplotlib.transforms.Bbox.overlaps`),
so that what is drawn is apart.
"""

from __future__ import annotations

import numpy as np


class Room:
    """The boxes (markers, legend, labels) and leader lines placed so far, and the curves."""

    def __init__(self, boxes: np.ndarray, curves: np.ndarray | None = None) -> None:
        self.boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
        self.lines = np.empty((0, 4))
        self.curves = np.empty((0, 4)) if curves is None else np.asarray(
            curves, dtype=float).reshape(-1, 4)

    def is_free(self, box: np.ndarray, line: np.ndarray | None, own: int) -> bool:
        """Whether a label's ``box`` and its leader ``line`` (None if it has none) meet nothing.

        ``own``: the row of the label's own marker among the boxes, which its line starts at.
        """
        if _boxes_overlap(box, self.boxes).any() or _segments_meet_boxes(
                np.vstack([self.lines, self.curves]), box[None]).any():
            return False
        if line is None:
            return True
        others = np.delete(self.boxes, own, axis=0)
        return not (_segments_meet_boxes(line[None], others).any()
                    or _segments_cross(line, self.lines).any())

    def take(self, box: np.ndarray, line: np.ndarray | None) -> None:
        """Keep ``box`` and ``line`` (if any) clear from now on."""
        self.boxes = np.vstack([self.boxes, box])
        if line is not None:
            self.lines = np.vstack([self.lines, line])


def _boxes_overlap(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Whether ``box`` overlaps (or touches) each row of ``boxes``."""
    return ((boxes[:, 0] <= box[2]) & (box[0] <= boxes[:, 2])
            & (boxes[:, 1] <= box[3]) & (box[1] <= boxes[:, 3]))


def _segments_meet_boxes(segments: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Whether each segment meets each box, (segments, boxes): Liang-Barsky clipping.

    The segment p + t d, 0 <= t <= 1, is inside a box for t in the intersection of the
    intervals where each coordinate is within the box's; it meets the box if that is not empty.
    """
    start = segments[:, None, :2]
    step = segments[:, None, 2:] - start
    low, high = boxes[None, :, :2], boxes[None, :, 2:]
    parallel = step == 0  # the coordinate is constant: within the box always or never
    within = (low <= start) & (start <= high)
    with np.errstate(divide="ignore", invalid="ignore"):
        to_low, to_high = (low - start) / step, (high - start) / step
    enter = np.where(parallel, np.where(within, -np.inf, np.inf), np.minimum(to_low, to_high))
    leave = np.where(parallel, np.where(within, np.inf, -np.inf), np.maximum(to_low, to_high))
    return np.maximum(enter.max(axis=-1), 0.0) <= np.minimum(leave.min(axis=-1), 1.0)


def _segments_cross(segment: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Whether ``segment`` meets each row of ``segments`` (collinear ones counted as meeting).

    Each segment's ends lie on both sides of (or on) the other's line.
    """
    p, q = segment[:2], segment[2:]
    a, b = segments[:, :2], segments[:, 2:]
    return ((_side(a, b, p) * _side(a, b, q) <= 0)
            & (_side(p[None], q[None], a) * _side(p[None], q[None], b) <= 0))


def _side(start: np.ndarray, end: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The cross product (end - start) x (point - start): > 0 left of the line, < 0 right."""
    return ((end[..., 0] - start[..., 0]) * (point[..., 1] - start[..., 1])
            - (end[..., 1] - start[..., 1]) * (point[..., 0] - start[..., 0]))
