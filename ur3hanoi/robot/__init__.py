"""The arm: what a UR robot is (registry), its kinematics (DH, URDF chain, Pinocchio model, IK), its joint
conventions and its controller's joint move.

- :mod:`~ur3hanoi.robot.registry`: the known robots (UR3, UR3e): DH table, limits, model sources.
- :mod:`~ur3hanoi.robot.chain`: SE(3) products, roll-pitch-yaw and the URDF chain's FK in NumPy.
- :mod:`~ur3hanoi.robot.urdf`: the URDF of a registered robot (example-robot-data's, or generated from DH).
- :mod:`~ur3hanoi.robot.model`: frames, limits, the tool offset and the Pinocchio model.
- :mod:`~ur3hanoi.robot.ik`: closed-form and numerical IK, branches.
- :mod:`~ur3hanoi.robot.convention`: controller vs course joint conventions.
- :mod:`~ur3hanoi.robot.movej`: the UR controller's ``movej`` profile.

Data: ``models/`` holds the MuJoCo robot folders (Menagerie layout).
"""
