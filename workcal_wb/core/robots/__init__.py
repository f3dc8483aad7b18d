"""Robot arms: models read from JSON files (model.py), closed-form kinematics in the controller's frames
(kinematics.py over opw.py and ur.py), the configuration data controllers store (configuration.py) and
where the links are at given joints (links.py)."""
from .kinematics import (forward, inverse, joint_margins_deg, limit_margin_deg, turn_candidates, turn_offsets,
                         within_limits, wrap_into_limits)
from .model import OpwParameters, Robot, UrParameters, builtin_robots, load_robot

__all__ = ["Robot", "OpwParameters", "UrParameters", "load_robot", "builtin_robots", "forward", "inverse",
           "within_limits", "joint_margins_deg", "limit_margin_deg", "turn_offsets", "turn_candidates",
           "wrap_into_limits"]
