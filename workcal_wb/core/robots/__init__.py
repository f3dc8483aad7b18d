"""Robot arms: models read from JSON files (model.py), closed-form kinematics in the controller's frames
(kinematics.py over opw.py and ur.py), and the configuration data controllers store (configuration.py)."""
from .kinematics import (forward, inverse, limit_margin_deg, turn_candidates, turn_offsets, within_limits,
                         wrap_into_limits)
from .model import OpwParameters, Robot, UrParameters, builtin_robots, load_robot

__all__ = ["Robot", "OpwParameters", "UrParameters", "load_robot", "builtin_robots", "forward", "inverse",
           "within_limits", "limit_margin_deg", "turn_offsets", "turn_candidates", "wrap_into_limits"]
