#!/usr/bin/env python3
"""Writes urdf/openarm.urdf: the OpenArm (v10) bimanual arm, both arms on one fixed pedestal.

Every number is a published kinematic or inertial fact (urdf/README.md, section `openarm.urdf`,
says where each comes from); the shapes are primitives of our own. Run from the repository
root: `python3 scripts/urdf/openarm.py > urdf/openarm.urdf`.
"""

import math

PI_2 = math.pi / 2

# (name, parent offset xyz, rpy as a function of reflect, axis as a function of reflect,
#  (lower, upper) for the right arm, left arm offset, velocity rad/s, effort N·m)
JOINTS = [
    ("joint1", (0, 0, 0.0625), lambda r: (0, 0, 0), lambda r: (0, 0, 1),
     (-1.396263, 3.490659), -2.094396, 16.754666, 40),
    ("joint2", (-0.0301, 0, 0.06), lambda r: (r * PI_2, 0, 0), lambda r: (-1, 0, 0),
     (-1.745329 + PI_2, 1.745329 + PI_2), -math.pi, 16.754666, 40),
    ("joint3", (0.0301, 0, 0.06625), lambda r: (0, 0, 0), lambda r: (0, 0, 1),
     (-1.570796, 1.570796), 0.0, 5.445426, 27),
    ("joint4", (0, 0.0315, 0.15375), lambda r: (0, 0, 0), lambda r: (0, 1, 0),
     (0.0, 2.443461), 0.0, 5.445426, 27),
    ("joint5", (0, -0.0315, 0.0955), lambda r: (0, 0, 0), lambda r: (0, 0, 1),
     (-1.570796, 1.570796), 0.0, 20.943946, 7),
    ("joint6", (0.0375, 0, 0.1205), lambda r: (0, 0, 0), lambda r: (1, 0, 0),
     (-0.785398, 0.785398), 0.0, 20.943946, 7),
    ("joint7", (-0.0375, 0, 0), lambda r: (0, 0, 0), lambda r: (0, r, 0),
     (-1.570796, 1.570796), 0.0, 20.943946, 7),
]

# (link, mass kg, CoM xyz, (ixx, iyy, izz, ixy, ixz, iyz)); a left arm mirrors y of the CoM
# (and so the sign of ixy and iyz).
LINKS = [
    ("link0", 1.1432, (-0.00095, 0.00016, 0.03077), (0.001128, 0.000962, 0.00147, 0, 0, 0)),
    ("link1", 1.1417, (0.00115, 0.00003, 0.05395), (0.001567, 0.001273, 0.001016, 0, 0, 0)),
    ("link2", 0.2775, (0.00840, 0, 0.03257), (0.000359, 0.000376, 0.000232, 0, -0.000109, 0)),
    ("link3", 1.0739, (-0.00210, 0.00055, 0.08847), (0.004372, 0.004319, 0.000661, 0, 0, 0)),
    ("link4", 0.5599, (-0.00290, -0.03031, 0.06340), (0.000623, 0.000511, 0.000334, 0, 0, 0)),
    ("link5", 0.5507, (-0.00305, 0.00089, 0.04308), (0.000423, 0.000445, 0.000324, 0, 0, 0)),
    ("link6", 0.3852, (-0.03714, 0.00033, -0.00009), (0.000143, 0.000157, 0.000159, 0, 0, 0)),
    ("link7", 0.3860, (0.00007, 0.01266, 0.06952), (0.000639, 0.000497, 0.000342, 0, 0, 8.9e-5)),
]

# Viscous damping of each joint (N·m·s/rad): the gearbox and bearings a disabled motor's
# shaft turns against. Not published: our estimate, larger for the 9:1 and 40:1 geared
# shoulder and elbow motors than for the wrist's, so a limp arm settles in about a second
# instead of swinging on. Index: joint1 … joint7, then the gripper.
DAMPING_NM_S_PER_RAD = [0.5, 0.5, 0.3, 0.3, 0.05, 0.05, 0.05, 0.02]

# A primitive per link (our own, for contacts and the views): cylinder radius, length, and
# its centre along the link's z.
SHAPES = {
    "link0": (0.045, 0.0625, 0.031),
    "link1": (0.045, 0.06, 0.03),
    "link2": (0.035, 0.066, 0.033),
    "link3": (0.035, 0.154, 0.077),
    "link4": (0.03, 0.0955, 0.048),
    "link5": (0.03, 0.12, 0.06),
    "link6": (0.025, 0.05, 0.0),
    "link7": (0.03, 0.08, 0.05),
}

# The gripper motor (J8) drives both fingers; the fingers open 0 … 44 mm. The motor's
# range to the fingers' travel is not published: 44 mm over 60° (1.0472 rad) is our
# estimate, the right arm opening at negative angles and the left at positive ones, as the
# vendor driver's ranges run (right −1.0472 … 0.4 rad, left −0.4 … 1.0472 rad).
FINGER_TRAVEL_M = 0.044
GRIPPER_OPEN_RAD = 1.0472


def fmt(values):
    return " ".join(f"{v:.9g}" for v in values)


def inertial(mass, com, inertia):
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    return (f'    <inertial><origin xyz="{fmt(com)}"/><mass value="{mass}"/>'
            f'<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="{ixy}" ixz="{ixz}" iyz="{iyz}"/>'
            f'</inertial>\n')


def shape(radius, length, centre_z):
    geometry = f'<geometry><cylinder radius="{radius}" length="{length}"/></geometry>'
    origin = f'<origin xyz="0 0 {centre_z}"/>'
    return (f"    <visual>{origin}{geometry}</visual>\n"
            f"    <collision>{origin}{geometry}</collision>\n")


def arm(side, reflect, mount_xyz, mount_rpy):
    p = f"{side}_"
    out = []
    out.append(f'  <joint name="{p}mount" type="fixed">\n'
               f'    <parent link="pedestal"/><child link="{p}link0"/>\n'
               f'    <origin xyz="{fmt(mount_xyz)}" rpy="{fmt(mount_rpy)}"/>\n  </joint>\n')
    for name, mass, com, inertia in LINKS:
        com = (com[0], reflect * com[1], com[2])
        ixx, iyy, izz, ixy, ixz, iyz = inertia
        inertia = (ixx, iyy, izz, reflect * ixy, ixz, reflect * iyz)
        out.append(f'  <link name="{p}{name}">\n' + inertial(mass, com, inertia)
                   + shape(*SHAPES[name]) + "  </link>\n")
    for k, (name, xyz, rpy, axis, (lower, upper), left_offset, velocity, effort) in enumerate(JOINTS):
        if reflect < 0:
            lower, upper = lower + left_offset, upper + left_offset
        out.append(f'  <joint name="{p}{name}" type="revolute">\n'
                   f'    <parent link="{p}link{k}"/><child link="{p}link{k + 1}"/>\n'
                   f'    <origin xyz="{fmt(xyz)}" rpy="{fmt(rpy(reflect))}"/>'
                   f'<axis xyz="{fmt(axis(reflect))}"/>\n'
                   f'    <limit lower="{lower:.6f}" upper="{upper:.6f}" effort="{effort}" velocity="{velocity}"/>\n'
                   f'    <dynamics damping="{DAMPING_NM_S_PER_RAD[k]}" friction="0"/>\n'
                   f'  </joint>\n')
    # Flange (joint8) and hand, both fixed.
    out.append(f'  <link name="{p}link8"/>\n'
               f'  <joint name="{p}joint8" type="fixed">\n'
               f'    <parent link="{p}link7"/><child link="{p}link8"/>\n'
               f'    <origin xyz="0.000001 {0.0205 * reflect:.4f} 0"/>\n  </joint>\n')
    out.append(f'  <link name="{p}hand">\n'
               + inertial(0.3, (0, 0.002 * reflect, 0.019), (0.0001, 0.00025, 0.00017, 0, 0, 0))
               + '    <visual><origin xyz="0 0 0.03"/><geometry><box size="0.04 0.1 0.06"/></geometry></visual>\n'
               + '    <collision><origin xyz="0 0 0.03"/><geometry><box size="0.04 0.1 0.06"/></geometry></collision>\n'
               + "  </link>\n"
               f'  <joint name="{p}hand_joint" type="fixed">\n'
               f'    <parent link="{p}link8"/><child link="{p}hand"/>\n'
               f'    <origin xyz="0 {-0.025 * reflect:.4f} 0.1001"/>\n  </joint>\n')
    # The gripper motor: a small drive wheel on the hand (its rotor's inertia is the
    # actuator's armature), the fingers following it through their <mimic>.
    g_lower, g_upper = (-GRIPPER_OPEN_RAD, 0.0) if reflect > 0 else (0.0, GRIPPER_OPEN_RAD)
    out.append(f'  <link name="{p}gripper_drive">\n'
               + inertial(0.01, (0, 0, 0), (1e-6, 1e-6, 1e-6, 0, 0, 0))
               + "  </link>\n"
               f'  <joint name="{p}gripper" type="revolute">\n'
               f'    <parent link="{p}hand"/><child link="{p}gripper_drive"/>\n'
               f'    <origin xyz="0 0 0.01"/><axis xyz="0 0 1"/>\n'
               f'    <limit lower="{g_lower:.4f}" upper="{g_upper:.4f}" effort="7" velocity="20.943946"/>\n'
               f'    <dynamics damping="{DAMPING_NM_S_PER_RAD[7]}" friction="0"/>\n'
               f'  </joint>\n')
    multiplier = -reflect * FINGER_TRAVEL_M / GRIPPER_OPEN_RAD
    for k, (y, axis_y) in enumerate([(0.0, -1), (0.012, 1)], start=1):
        out.append(f'  <link name="{p}finger{k}">\n'
                   + inertial(0.036, (0.00645, 0.01702 * (1 if k == 1 else -1), 0.02197),
                              (2.375e-6, 2.375e-6, 7.5e-7, 0, 0, 0))
                   + '    <visual><origin xyz="0 0 0.03"/><geometry><box size="0.02 0.01 0.05"/></geometry></visual>\n'
                   + '    <collision><origin xyz="0 0 0.03"/><geometry><box size="0.02 0.01 0.05"/></geometry></collision>\n'
                   + "  </link>\n"
                   f'  <joint name="{p}finger_joint{k}" type="prismatic">\n'
                   f'    <parent link="{p}hand"/><child link="{p}finger{k}"/>\n'
                   f'    <origin xyz="0 {y} 0.015"/><axis xyz="0 {axis_y} 0"/>\n'
                   f'    <limit lower="0" upper="{FINGER_TRAVEL_M}" effort="333" velocity="10"/>\n'
                   f'    <mimic joint="{p}gripper" multiplier="{multiplier:.6f}" offset="0"/>\n'
                   f'  </joint>\n')
    return "".join(out)


def main():
    print('<?xml version="1.0"?>')
    print("<!-- The OpenArm (v10): two 7-DoF arms of Damiao motors with grippers on one pedestal.\n"
          "     Written by scripts/urdf/openarm.py; numbers and their sources: urdf/README.md. -->")
    print('<robot name="openarm">')
    print('  <link name="pedestal">\n'
          + inertial(10.0, (0, 0, 0.35), (0.5, 0.5, 0.05, 0, 0, 0))
          + shape(0.05, 0.68, 0.34) + "  </link>")
    print(arm("right", 1, (0, -0.031, 0.698), (PI_2, 0, 0)), end="")
    print(arm("left", -1, (0, 0.031, 0.698), (-PI_2, 0, 0)), end="")
    print("</robot>")


if __name__ == "__main__":
    main()
