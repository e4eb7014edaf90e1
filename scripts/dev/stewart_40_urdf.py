#!/usr/bin/env python3
"""Writes urdf/stewart_40.urdf and urdf/stewart_40_near_singular.urdf: 6-6 Stewart-Gough platforms
with nearly 40 real assemblies.

The geometry starts from Dietmaier's published platform with 40 real assemblies (P. Dietmaier,
"The Stewart-Gough platform of general geometry can have 40 real postures", Advances in Robot
Kinematics, Kluwer 1998; the numbers as PHCpack's demo `stewgou40` states them, read back from
its polynomial coefficients): platform point p_i (platform frame), base point b_i, leg length L_i.
Every point coordinate is then moved by a seeded normal offset of e metres (the
platform is about one metre across) and every length by e of itself, written with six
decimals: instances of our own, whose assemblies scripts/dev/stewart_fk.py computes from the file
alone. Dietmaier's assemblies include pairs about to merge; a perturbation turns some pairs
complex (1e-3 keeps 26 to 34 real, 3e-4 32 to 36, 1e-4 34 to 38) and leaves others nearer still:
 - stewart_40.urdf, e = 3e-4 (seed 40): 36 real, the least singular value of a leg Jacobian 1.1e-3;
 - stewart_40_near_singular.urdf, e = 1e-4 (seed 39): 38 real, three below 1.3e-4 (the least 3.8e-5).

Run: python3 scripts/dev/stewart_40_urdf.py   (numpy; prints each file's leg lengths for --fix)
"""
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))

# (p_i, b_i, L_i), Dietmaier 1998.
DIETMAIER = [
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 1.0),
    ((0.542805, 0.0, 0.0), (1.107915, 0.0, 0.0), 0.645275),
    ((0.956919, -0.528915, 0.0), (0.549094, 0.756063, 0.0), 1.086284),
    ((0.665885, -0.353482, 1.402538), (0.735077, -0.223935, 0.525991), 1.503439),
    ((0.478359, 1.158742, 0.107672), (0.514188, -0.526063, -0.368418), 1.281933),
    ((-0.137087, -0.235121, 0.353913), (0.590473, 0.094733, -0.205018), 0.771071),
]
# file name: perturbation, seed, real assemblies, the least singular value of a leg Jacobian
FIXTURES = {
    "stewart_40": (3e-4, 40, 36, "1.1e-3"),
    "stewart_40_near_singular": (1e-4, 39, 38, "3.8e-5"),
}

HEADER = """<?xml version="1.0"?>
<!--
  A 6-6 Stewart-Gough platform with {real} real assemblies of its 40 complex ones at the leg lengths
  below: Dietmaier's platform of 40 real assemblies (Advances in Robot Kinematics, 1998), each
  ball centre coordinate moved by a seeded normal offset of {pert:g} m and each length by {pert:g}
  of itself, rounded to the micrometre (scripts/dev/stewart_40_urdf.py, seed {seed}). Base and
  platform are far from planar or symmetric; several assemblies are close to a singularity of the
  leg Jacobian (smallest singular value {least}).
  Same structure as urdf/stewart_6_6.urdf: leg i joins base ball b_i (origin of joint leg{{i}}_base)
  to platform ball p_i (successor origin of loop leg{{i}}_top) through a spherical joint, a
  cylinder, a prismatic joint leg{{i}} along z (its value IS the ball-to-ball length, metres), a
  rod and a <loop type="spherical"> onto the platform, which hangs from the base by a floating
  joint (platform_pose; its origin is only a rest pose).
  Leg lengths of the {real} assemblies (tests/data/{name}_fk.json, scripts/dev/stewart_fk.py):
  {fix}
-->
<robot name="{name}">
  <link name="base">
    <visual>
      <geometry><cylinder length="0.02" radius="1.2"/></geometry>
      <origin xyz="0 0 -0.01" rpy="0 0 0"/>
    </visual>
  </link>
  <link name="platform">
    <visual>
      <geometry><cylinder length="0.02" radius="1.2"/></geometry>
      <origin xyz="0 0 0.01" rpy="0 0 0"/>
    </visual>
  </link>
  <joint name="platform_pose" type="floating">
    <parent link="base"/>
    <child link="platform"/>
    <origin xyz="0 0 1" rpy="0 0 0"/>
  </joint>
"""

LEG = """  <!-- leg {i} -->
  <link name="leg{i}_cylinder">
    <visual>
      <geometry><cylinder length="0.4" radius="0.025"/></geometry>
      <origin xyz="0 0 0.2" rpy="0 0 0"/>
    </visual>
  </link>
  <link name="leg{i}_rod">
    <visual>
      <geometry><cylinder length="0.4" radius="0.015"/></geometry>
      <origin xyz="0 0 -0.2" rpy="0 0 0"/>
    </visual>
  </link>
  <joint name="leg{i}_base" type="spherical">
    <parent link="base"/>
    <child link="leg{i}_cylinder"/>
    <origin xyz="{b}" rpy="0 0 0"/>
  </joint>
  <joint name="leg{i}" type="prismatic">
    <parent link="leg{i}_cylinder"/>
    <child link="leg{i}_rod"/>
    <axis xyz="0 0 1"/>
    <limit lower="0.4" upper="2.0" effort="0" velocity="0"/>
  </joint>
"""

LOOP = """  <loop name="leg{i}_top" type="spherical">
    <predecessor link="leg{i}_rod"><origin xyz="0 0 0" rpy="0 0 0"/></predecessor>
    <successor link="platform"><origin xyz="{p}" rpy="0 0 0"/></successor>
  </loop>
"""


def decimal(x):
    s = f"{x:.6f}"
    return "0" if float(s) == 0 else s.rstrip("0").rstrip(".")


def perturbed(perturbation, seed):
    rng = np.random.default_rng(seed)
    legs = []
    for p, b, length in DIETMAIER:
        p = np.array(p) + perturbation * rng.standard_normal(3)
        b = np.array(b) + perturbation * rng.standard_normal(3)
        length = length * (1 + perturbation * rng.standard_normal())
        legs.append(([decimal(x) for x in p], [decimal(x) for x in b], decimal(length)))
    return legs


def main():
    for name, (perturbation, seed, real, least) in FIXTURES.items():
        legs = perturbed(perturbation, seed)
        lengths = " ".join(f"leg{i}={L}" for i, (_, _, L) in enumerate(legs, 1))
        text = HEADER.format(name=name, pert=perturbation, seed=seed, real=real, least=least, fix=lengths)
        text += "".join(LEG.format(i=i, b=" ".join(b)) for i, (_, b, _) in enumerate(legs, 1))
        text += "".join(LOOP.format(i=i, p=" ".join(p)) for i, (p, _, _) in enumerate(legs, 1))
        text += "</robot>\n"
        with open(os.path.join(REPO, "urdf", f"{name}.urdf"), "w") as f:
            f.write(text)
        print(f"{name}: " + " ".join(f"--fix {x}" for x in lengths.split()))


if __name__ == "__main__":
    main()
