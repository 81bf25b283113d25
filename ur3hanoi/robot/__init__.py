"""The arm: what a UR robot is (registry), its kinematics (DH, URDF chain, Pinocchio model, IK), its joint
conventions and its controller's joint move.

- :mod:`~ur3hanoi.robot.registry`: the known robots (UR3, UR3e): DH table, limits, model sources; the one home of
  their numbers.
- :mod:`~ur3hanoi.robot.dh`: the one DH matrix (one joint, scalar or batched) and FK from a DH table.
- :mod:`~ur3hanoi.robot.chain`: SE(3) products, roll-pitch-yaw and the URDF chain's FK in NumPy.
- :mod:`~ur3hanoi.robot.urdf`: the URDF of a registered robot (example-robot-data's, or generated from DH), its
  joint names and the tool offset (``tcp`` link).
- :mod:`~ur3hanoi.robot.model`: frames, limits and the model (NumPy chain FK, Pinocchio model).
- :mod:`~ur3hanoi.robot.ik_solvers`: the IK result type and the numerical solvers (Pinocchio, placo).
- :mod:`~ur3hanoi.robot.ik`: the closed-form IK, branches, and the branch policy tables use.
- :mod:`~ur3hanoi.robot.convention`: controller vs course joint conventions.
- :mod:`~ur3hanoi.robot.movej`: the UR controller's ``movej`` profile.

Data: ``models/`` holds the MuJoCo robot folders (Menagerie layout).
"""
