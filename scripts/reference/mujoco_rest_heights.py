#!/usr/bin/env python3
"""Where unpowered legged robots come to rest after a short drop, measured in MuJoCo.

An independent reference for the rest heights printed by the simulator's
`sim/examples/urdf_corpus.rs` (the "rest height m (3 s unpowered)" column). It replicates
that drop as closely as MuJoCo allows:

* the URDF's root link is a free body (a freejoint is added to it), starting level;
* every joint at position 0, clamped into its limits; joint limits active;
* no actuation (zero torque); URDF `<dynamics damping friction>` applied as joint
  `damping` and `frictionloss`;
* gravity -9.81 z; a ground plane at z = 0; friction 0.5 on every geom (MuJoCo takes the
  larger of the two geoms' coefficients, so contacts get 0.5); condim 3;
* collision geometry = the URDF's `<collision>` shapes (visuals are dropped); meshes
  collide as their convex hulls (MuJoCo's default for mesh geoms);
* no self-collision: robot geoms contype=1 conaffinity=0, floor contype=0 conaffinity=1,
  so only robot-floor pairs pass MuJoCo's (c1 & a2) || (c2 & a1) test;
* the start height puts the LOWEST collision point (at the start pose) 2 cm above z = 0;
* timestep 0.25 ms (the simulator's 1 ms step is 4 substeps of 0.25 ms), 3 s simulated;
* default MuJoCo contact model otherwise (soft contacts, solref 0.02 1, solimp
  0.9 0.95 0.001, pyramidal cone, Newton solver, Euler integrator).

Bodies joined by fixed joints are NOT fused (compiler fusestatic="false");
balanceinertia="true" lets URDF inertias violating the triangle inequality load;
inertiafromgeom="false" keeps a link without <inertial> massless as URDF says (otherwise
MuJoCo gives anymal_c's `base` 29 kg from its geoms); a link whose full inertia tensor is
not positive definite (1e-6 kg dummies with all six entries 1e-6) loses its off-diagonal
terms, since MuJoCo refuses it (printed as a note).

Printed per robot: the root origin's height MuJoCo started from, the root origin's height
after 3 s ("sim m" beside it: the simulator's number), the root body's speed (linear m/s
and angular rad/s) at the end, the lowest point of any collision geom at the end (mesh
geoms: their lowest vertex, i.e. hull vertex), and the world z components of the root's
z axis ("up.z", 1 = upright) and x axis ("fwd.z", 1 = lying on its back, -1 = face down).

Run (MuJoCo from PyPI, not part of the project's dependencies):

    python3 -m venv /tmp/mjvenv && /tmp/mjvenv/bin/pip install mujoco==4.0.1 numpy
    /tmp/mjvenv/bin/python scripts/reference/mujoco_rest_heights.py [CORPUS]

where CORPUS is `.../cmeel.prefix/share/example-robot-data` of the PyPI package
example-robot-data 6.0.0 (default: $ARMHIL_URDF_CORPUS, else
/tmp/erd/unpacked/cmeel.prefix/share/example-robot-data). `--stiff` additionally runs
every robot with a stiffer contact (solref 0.002 1, solimp 0.95 0.99 0.001) to show how
much of the result is MuJoCo's contact softness.
"""

import os
import re
import sys
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

ROBOTS = [
    ("a1", "robots/a1_description/urdf/a1.urdf"),
    ("anymal_b", "robots/anymal_b_simple_description/robots/anymal.urdf"),
    ("anymal_c", "robots/anymal_c_simple_description/urdf/anymal.urdf"),
    ("g1_29dof", "robots/g1_description/urdf/g1_29dof_rev_1_0.urdf"),
    ("go1", "robots/go1_description/urdf/go1.urdf"),
    ("solo12", "robots/solo_description/robots/solo12.urdf"),
    ("talos_reduced", "robots/talos_data/robots/talos_reduced.urdf"),
]

# The simulator's numbers (root height after 3 s, m), for the side-by-side column.
SIMULATOR = {
    "a1": 0.0567,
    "anymal_b": 0.1356,
    "anymal_c": 0.0899,
    "g1_29dof": 0.1172,
    "go1": 0.0567,
    "solo12": 0.0279,
    "talos_reduced": 0.1207,
}

DROP_HEIGHT_M = 0.02
TIMESTEP_S = 0.00025
DURATION_S = 3.0
FRICTION = 0.5

COMPILER_BLOCK = (
    '<mujoco><compiler discardvisual="true" balanceinertia="true" '
    'strippath="false" fusestatic="false" inertiafromgeom="false"/></mujoco>'
)


def prepared_urdf(corpus, relative):
    """The URDF text with absolute mesh paths, no visuals, and a MuJoCo compiler block.

    Also returns {joint name: (damping, friction)} from the URDF's <dynamics> and the links
    whose inertia tensor is not positive definite (MuJoCo refuses those): their
    off-diagonal products of inertia are dropped (go1's 1e-6 kg `base` has all six = 1e-6)."""
    path = os.path.join(corpus, relative)
    root = ET.parse(path).getroot()
    fixed_inertia = []
    for link in root.findall("link"):
        inertia = link.find("inertial/inertia")
        if inertia is None:
            continue
        v = {k: float(inertia.get(k, 0.0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        tensor = np.array(
            [
                [v["ixx"], v["ixy"], v["ixz"]],
                [v["ixy"], v["iyy"], v["iyz"]],
                [v["ixz"], v["iyz"], v["izz"]],
            ]
        )
        off_diagonal = any(v[k] != 0.0 for k in ("ixy", "ixz", "iyz"))
        if off_diagonal and np.linalg.eigvalsh(tensor).min() <= 0.0:
            for k in ("ixy", "ixz", "iyz"):
                inertia.set(k, "0")
            fixed_inertia.append(link.get("name"))
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
    for mesh in root.iter("mesh"):
        name = mesh.get("filename")
        resolved = re.sub(r"^package:///?example-robot-data/", corpus.rstrip("/") + "/", name)
        if not os.path.isabs(resolved):
            resolved = os.path.join(os.path.dirname(path), resolved)
        if not os.path.exists(resolved):
            raise FileNotFoundError(resolved)
        mesh.set("filename", resolved)
    dynamics = {}
    for joint in root.findall("joint"):
        d = joint.find("dynamics")
        if d is not None:
            dynamics[joint.get("name")] = (
                float(d.get("damping", 0.0)),
                float(d.get("friction", 0.0)),
            )
    text = ET.tostring(root, encoding="unicode")
    text = re.sub(r"(<robot\b[^>]*>)", r"\1" + COMPILER_BLOCK, text, count=1)
    return text, dynamics, fixed_inertia


def build(corpus, relative, stiff=False):
    """The compiled model: robot on a free root body above a floor plane."""
    text, dynamics, fixed_inertia = prepared_urdf(corpus, relative)
    spec = mujoco.MjSpec.from_string(text)
    spec.option.timestep = TIMESTEP_S
    spec.option.gravity = [0.0, 0.0, -9.81]

    roots = list(spec.worldbody.bodies)
    if len(roots) != 1:
        raise RuntimeError(f"expected one root body, got {[b.name for b in roots]}")
    root = roots[0]
    if list(root.joints):
        raise RuntimeError(f"root body {root.name} already has joints")
    root.add_freejoint()

    for joint in spec.joints:
        if joint.name in dynamics:
            damping, friction = dynamics[joint.name]
            # MuJoCo 4's joint damping is a 3-vector; its first term is the linear
            # (viscous) coefficient.
            joint.damping = [damping, 0.0, 0.0]
            joint.frictionloss = friction

    for geom in spec.geoms:
        geom.contype, geom.conaffinity = 1, 0
        geom.friction = [FRICTION, 0.005, 0.0001]
        geom.condim = 3
        if stiff:
            geom.solref = [0.002, 1.0]
            geom.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
    floor = spec.worldbody.add_geom(
        name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 1.0]
    )
    floor.contype, floor.conaffinity = 0, 1
    floor.friction = [FRICTION, 0.005, 0.0001]
    if stiff:
        floor.solref = [0.002, 1.0]
        floor.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]

    model = spec.compile()
    return model, root.name, check_meshes(spec, text), fixed_inertia


def check_meshes(spec, urdf_text):
    """MuJoCo names URDF meshes by file stem: make sure no two files share one mesh."""
    files = {m.get("filename") for m in ET.fromstring(urdf_text).iter("mesh")}
    used = {m.file for m in spec.meshes}
    missing = {f for f in files if f not in used}
    return sorted(missing)


def lowest_point(model, data):
    """The lowest z of any robot collision geom (the floor excluded)."""
    low = np.inf
    for g in range(model.ngeom):
        kind = int(model.geom_type[g])
        if kind == mujoco.mjtGeom.mjGEOM_PLANE:
            continue
        pos = data.geom_xpos[g]
        rot = data.geom_xmat[g].reshape(3, 3)
        size = model.geom_size[g]
        if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
            z = pos[2] - size[0]
        elif kind == mujoco.mjtGeom.mjGEOM_BOX:
            z = pos[2] - np.abs(rot[2, :]) @ size
        elif kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
            az = rot[2, 2]
            z = pos[2] - abs(az) * size[1] - size[0] * np.sqrt(max(0.0, 1.0 - az * az))
        elif kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            z = pos[2] - abs(rot[2, 2]) * size[1] - size[0]
        elif kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            z = pos[2] - np.sqrt(((rot[2, :] * size) ** 2).sum())
        elif kind == mujoco.mjtGeom.mjGEOM_MESH:
            mesh = model.geom_dataid[g]
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            verts = model.mesh_vert[start : start + count]
            z = pos[2] + (verts @ rot[2, :]).min()
        else:
            raise RuntimeError(f"geom type {kind} not handled")
        low = min(low, z)
    return low


def drop(corpus, relative, stiff=False):
    model, root_name, unmatched, fixed_inertia = build(corpus, relative, stiff)
    data = mujoco.MjData(model)
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, root_name)
    free = model.body_jntadr[root]
    qadr = model.jnt_qposadr[free]

    # Joints at 0, clamped into their limits; the root level at the origin.
    data.qpos[:] = 0.0
    data.qpos[qadr + 3] = 1.0
    for j in range(model.njnt):
        if int(model.jnt_type[j]) in (
            int(mujoco.mjtJoint.mjJNT_HINGE),
            int(mujoco.mjtJoint.mjJNT_SLIDE),
        ):
            if model.jnt_limited[j]:
                lo, hi = model.jnt_range[j]
                data.qpos[model.jnt_qposadr[j]] = min(max(0.0, lo), hi)
    mujoco.mj_kinematics(model, data)
    start = DROP_HEIGHT_M - lowest_point(model, data)
    data.qpos[qadr + 2] = start
    mujoco.mj_forward(model, data)

    for _ in range(int(round(DURATION_S / TIMESTEP_S))):
        mujoco.mj_step(model, data)
    if not np.all(np.isfinite(data.qpos)):
        raise RuntimeError("state not finite")

    dadr = model.jnt_dofadr[free]
    linear = np.linalg.norm(data.qvel[dadr : dadr + 3])
    angular = np.linalg.norm(data.qvel[dadr + 3 : dadr + 6])
    mujoco.mj_kinematics(model, data)
    axes = data.xmat[root].reshape(3, 3)
    return {
        "up": axes[2, 2],
        "fwd": axes[2, 0],
        "start": start,
        "final": data.xpos[root][2],
        "linear": linear,
        "angular": angular,
        "low": lowest_point(model, data),
        "mass": model.body_subtreemass[root],
        "root": root_name,
        "unmatched": unmatched,
        "fixed_inertia": fixed_inertia,
    }


def main(argv):
    stiff = "--stiff" in argv
    args = [a for a in argv if not a.startswith("--")]
    corpus = (
        args[0]
        if args
        else os.environ.get(
            "ARMHIL_URDF_CORPUS", "/tmp/erd/unpacked/cmeel.prefix/share/example-robot-data"
        )
    )
    print(f"MuJoCo {mujoco.__version__}, timestep {TIMESTEP_S * 1e3:g} ms, {DURATION_S:g} s")
    variants = [("default", False)] + ([("stiff", True)] if stiff else [])
    print(
        f"{'robot':<14} {'contact':<8} {'root':<14} {'mass kg':>8} {'start m':>8} "
        f"{'final m':>8} {'sim m':>7} {'|v| m/s':>8} {'|w| rad/s':>9} {'lowest m':>9} "
        f"{'up.z':>5} {'fwd.z':>5}"
    )
    for name, relative in ROBOTS:
        for label, flag in variants:
            try:
                r = drop(corpus, relative, flag)
            except Exception as e:  # noqa: BLE001 - report and go on
                print(f"{name:<14} {label:<8} FAILED: {e}")
                continue
            print(
                f"{name:<14} {label:<8} {r['root']:<14} {r['mass']:8.2f} {r['start']:8.4f} "
                f"{r['final']:8.4f} {SIMULATOR.get(name, float('nan')):7.4f} "
                f"{r['linear']:8.5f} {r['angular']:9.5f} {r['low']:9.5f} "
                f"{r['up']:5.2f} {r['fwd']:5.2f}"
            )
            if r["fixed_inertia"] and not flag:
                print(f"  note: off-diagonal inertia dropped on {r['fixed_inertia']}")
            if r["unmatched"]:
                print(f"  warning: mesh files not loaded as their own mesh: {r['unmatched']}")


if __name__ == "__main__":
    main(sys.argv[1:])
