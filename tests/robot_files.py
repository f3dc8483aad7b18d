"""Robot files the robot tests write for themselves: arms of the controllers the library may lack, and the
J2/J3 coupling, whatever the built-in library holds."""
import json
from pathlib import Path

from workcal_wb.core.robots import Robot, load_robot

# ABB IRB 2400/10 and /16 (the same arm): opw_kinematics' makeIrb2400_10 (checked there against IKFast),
# limits of ros-industrial/abb abb_irb2400_support; a parallel arm, whose controller J3 is the forearm's
# angle: the model's joint 3 is J3 - J2 (abb_driver J23_coupled).
ABB_IRB2400 = {
    "id": "test_abb_irb2400", "name": "ABB IRB 2400 (test file)", "controller": "abb", "kinematics": "opw",
    "opw": {"a1": 100.0, "a2": -135.0, "b": 0.0, "c1": 615.0, "c2": 705.0, "c3": 755.0, "c4": 85.0,
            "offsets_deg": [0, 0, -90, 0, 0, 0], "signs": [1, 1, 1, 1, 1, 1], "j23_factor": -1},
    "joint_limits_deg": [[-180, 180], [-100, 110], [-60, 65], [-200, 200], [-120, 120], [-400, 400]],
}

# FANUC M-10iA: ros-industrial/fanuc fanuc_m10ia_support opw parameters; FANUC's J3 is measured against the
# horizontal: the model's joint 3 is J3 + J2 (fanuc_driver J23_factor).
FANUC_M10IA = {
    "id": "test_fanuc_m10ia", "name": "FANUC M-10iA (test file)", "controller": "fanuc", "kinematics": "opw",
    "opw": {"a1": 150.0, "a2": -200.0, "b": 0.0, "c1": 450.0, "c2": 600.0, "c3": 640.0, "c4": 100.0,
            "offsets_deg": [0, 0, -90, 0, 0, 180], "signs": [1, 1, -1, -1, -1, -1], "j23_factor": 1},
    "joint_limits_deg": [[-170, 170], [-90, 160], [-180, 267], [-190, 190], [-140, 140], [-270, 270]],
    "base": [0, 0, 450, 0, 0, 0],
}


def write_robot(folder: Path, data: dict) -> Robot:
    """Write a robot file into ``folder`` and load it as a user's file."""
    path = Path(folder) / f"{data['id']}.json"
    path.write_text(json.dumps(data))
    return load_robot(path)
