"""The official UR driver's ROS 1 messages, generated from the vendored texts: every md5sum of the fact sheet
(``../shared/lab/ur-driver-interface.md`` section 3), the Debian-packaged ones included."""

from __future__ import annotations

import importlib

import pytest

from tests.support.ros_support import requires_ros

pytestmark = requires_ros

# ../shared/lab/ur-driver-interface.md, section 3 (type: md5).
FACT_SHEET = {
    "std_msgs/Header": "2176decaecbce78abc3b96ef049fabed",
    "std_msgs/Float64": "fdb28210bfa9d7c91146260178d9a584",
    "actionlib_msgs/GoalID": "302881f31927c1df708a2dbab0e80ee8",
    "actionlib_msgs/GoalStatus": "d388f9b87b3c471f784434d671988d4a",
    "actionlib_msgs/GoalStatusArray": "8b2b82f13216d0a8ea88bd3af735e619",
    "sensor_msgs/JointState": "3066dcd76a6cfaef579bd0f34173e9fd",
    "trajectory_msgs/JointTrajectoryPoint": "f3cd1e1c4d320c79d6985c904ae5dcd3",
    "trajectory_msgs/JointTrajectory": "65b4f94a94d1ed67169da35a02f33d3f",
    "control_msgs/JointTolerance": "f544fe9c16cf04547e135dd6063ff5be",
    "control_msgs/FollowJointTrajectoryGoal": "69636787b6ecbde4d61d711979bc7ecb",
    "control_msgs/FollowJointTrajectoryResult": "493383b18409bfb604b4e26c676401d2",
    "control_msgs/FollowJointTrajectoryFeedback": "10817c60c2486ef6b33e97dcd87f4474",
    "control_msgs/FollowJointTrajectoryActionGoal": "cff5c1d533bf2f82dd0138d57f4304bb",
    "control_msgs/FollowJointTrajectoryActionResult": "c4fb3b000dc9da4fd99699380efcc5d9",
    "control_msgs/FollowJointTrajectoryActionFeedback": "d8920dc4eae9fc107e00999cce4be641",
    "control_msgs/FollowJointTrajectoryAction": "bc4f9b743838566551c0390c65f1a248",
    "ur_msgs/Digital": "83707be3fa18d2ffe57381ea034aa262",
    "ur_msgs/Analog": "6be678008703fe11fbea12281a3d6d23",
    "ur_msgs/IOStates": "b341cc0bc3ea976e9cacf81c26adeb88",
}
SET_IO = {  # (service, request, response); with PIN_* = current Noetic (ur_msgs 1.4.x), without = 1.3.x
    "with PIN_*": ("f539fc0b1a42859fb186a5aaba22d4b0", "8e9d2a7211150d4126b8813c554cb6ed",
                   "358e233cde0c8a8bcfea4ce193f8fc15"),
    "without PIN_*": ("e1b580ccf43a938f2efbbb98bbe3e277", "85200c86fbe60ea3e047bae3d6574bfd",
                      "358e233cde0c8a8bcfea4ce193f8fc15"),
}


def generated() -> dict[str, object]:
    from ur3hanoi.interface.ros1.driver_msgs import load_driver_messages

    m = load_driver_messages()
    action = m.FollowJointTrajectoryAction()
    classes = [m.FollowJointTrajectoryAction, m.FollowJointTrajectoryGoal, m.FollowJointTrajectoryResult,
               m.FollowJointTrajectoryFeedback, m.JointTolerance, m.JointTrajectory, m.JointTrajectoryPoint,
               m.IOStates, m.Digital, m.Analog, type(action.action_goal), type(action.action_result),
               type(action.action_feedback), type(action.action_goal.header), type(action.action_goal.goal_id),
               type(action.action_result.status)]
    return {c._type: c for c in classes}


def test_every_generated_class_has_the_official_md5sum():
    classes = generated()
    ours = {t: c._md5sum for t, c in classes.items()}  # type: ignore[attr-defined]
    assert {t: FACT_SHEET[t] for t in ours} == ours
    assert set(FACT_SHEET) - set(ours) == {"std_msgs/Float64", "actionlib_msgs/GoalStatusArray",
                                           "sensor_msgs/JointState"}  # used from Debian: checked below


def test_the_debian_packaged_messages_have_the_fact_sheets_md5sums():
    from ur3hanoi.interface.ros1.env import ensure_ros_python

    ensure_ros_python()
    for t in ("std_msgs/Float64", "actionlib_msgs/GoalStatusArray", "sensor_msgs/JointState",
              "trajectory_msgs/JointTrajectory", "actionlib_msgs/GoalID"):
        pkg, name = t.split("/")
        assert getattr(importlib.import_module(f"{pkg}.msg"), name)._md5sum == FACT_SHEET[t], t


@pytest.mark.parametrize("version", list(SET_IO))
def test_both_set_io_texts(version):
    from ur3hanoi.interface.ros1.driver_msgs import load_driver_messages

    m = load_driver_messages()
    srv = m.SetIO if version == "with PIN_*" else m.SetIO13
    assert (srv._md5sum, srv._request_class._md5sum, srv._response_class._md5sum) == SET_IO[version]
    assert srv._type == "ur_msgs/SetIO"
    assert hasattr(m.SetIO._request_class, "PIN_DOUT1") and not hasattr(m.SetIO13._request_class, "PIN_DOUT1")


def test_the_station_answers_clients_of_either_text():
    from ur3hanoi.interface.ros1.ur_server import EitherSetIoSum

    advertised = EitherSetIoSum(SET_IO["with PIN_*"][0])
    for client in (SET_IO["with PIN_*"][0], SET_IO["without PIN_*"][0]):
        assert (client != advertised) is False  # rospy's server check: `md5sum != service_class._md5sum`
    other = "0" * 32
    assert (other != advertised) is True and str(advertised) == SET_IO["with PIN_*"][0]


def test_the_action_expands_like_genaction():
    from ur3hanoi.interface.ros1.driver_msgs import AUTOGEN, action_texts, ros1_text

    texts = action_texts("control_msgs/FollowJointTrajectory", ros1_text("control_msgs/FollowJointTrajectory"))
    assert len(texts) == 7 and all(t.startswith(AUTOGEN) for t in texts.values())
    assert "actionlib_msgs/GoalID goal_id\nFollowJointTrajectoryGoal goal" in \
        texts["control_msgs/FollowJointTrajectoryActionGoal"]
