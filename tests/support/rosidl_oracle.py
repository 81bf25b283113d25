"""An oracle for the UR driver's ROS 2 types that shares no code with rosidl: rosbags parses the vendored ``.msg``,
``.srv`` and ``.action`` texts, the types rosidl derives from a service or an action are spelled out here from its
documented rules, and rosbags computes their RIHS01 hashes.

rosidl's rules (ros2/rosidl ``rosidl_parser/rosidl_parser/definition.py``, REP 2011 for the hashes): an unqualified
type in an interface file names ``<package>/msg/<Type>``; a service ``S`` gives ``S_Request``, ``S_Response``,
``S_Event`` (``service_msgs/ServiceEventInfo info``, ``S_Request[<=1] request``, ``S_Response[<=1] response``) and
``S`` itself (``request_message``, ``response_message``, ``event_message``); an action ``A`` gives ``A_Goal``,
``A_Result``, ``A_Feedback``, the services ``A_SendGoal`` (request: ``unique_identifier_msgs/UUID goal_id``,
``A_Goal goal``; response: ``bool accepted``, ``builtin_interfaces/Time stamp``) and ``A_GetResult`` (request:
``goal_id``; response: ``int8 status``, ``A_Result result``), ``A_FeedbackMessage`` (``goal_id``, ``A_Feedback
feedback``) and ``A`` itself (``goal``, ``result``, ``feedback``, ``send_goal_service``, ``get_result_service``,
``feedback_message``)."""

from __future__ import annotations

import re
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

UUID = "unique_identifier_msgs/msg/UUID"


def _name(t: str) -> tuple[Any, ...]:
    return (Nodetype.NAME, t)


def _base(t: str) -> tuple[Any, ...]:
    return (Nodetype.BASE, (t, 0))


def _at_most_one(t: str) -> tuple[Any, ...]:
    return (Nodetype.SEQUENCE, (_name(t), 1))


def _parse(text: str, full: str) -> tuple[Any, Any]:
    """``text`` as the type ``full`` (``pkg/<msg|srv|action>/Name``), unqualified types resolved to ``pkg/msg``."""
    pkg, _, name = full.split("/")
    consts, fields = get_types_from_msg(text, f"{pkg}/msg/{name}")[f"{pkg}/msg/{name}"]
    return consts, fields


def _service(full: str, request: tuple[Any, Any], response: tuple[Any, Any]) -> dict[str, Any]:
    return {
        f"{full}_Request": request, f"{full}_Response": response,
        f"{full}_Event": ([], [("info", _name("service_msgs/msg/ServiceEventInfo")),
                               ("request", _at_most_one(f"{full}_Request")),
                               ("response", _at_most_one(f"{full}_Response"))]),
        full: ([], [("request_message", _name(f"{full}_Request")), ("response_message", _name(f"{full}_Response")),
                    ("event_message", _name(f"{full}_Event"))]),
    }


def srv_types(text: str, full: str) -> dict[str, Any]:
    """The types rosidl makes of a ``.srv`` text (``full`` = ``pkg/srv/Name``)."""
    request, response = re.split(r"(?:^|\n)---\n", text, maxsplit=1)  # an empty request: the text starts with ---
    return _service(full, _parse(request, f"{full}_Request"), _parse(response, f"{full}_Response"))


def action_types(text: str, full: str) -> dict[str, Any]:
    """The types rosidl makes of an ``.action`` text (``full`` = ``pkg/action/Name``)."""
    goal, result, feedback = text.split("\n---\n")
    out = {f"{full}_Goal": _parse(goal, f"{full}_Goal"), f"{full}_Result": _parse(result, f"{full}_Result"),
           f"{full}_Feedback": _parse(feedback, f"{full}_Feedback"),
           f"{full}_FeedbackMessage": ([], [("goal_id", _name(UUID)), ("feedback", _name(f"{full}_Feedback"))])}
    out.update(_service(f"{full}_SendGoal",
                        ([], [("goal_id", _name(UUID)), ("goal", _name(f"{full}_Goal"))]),
                        ([], [("accepted", _base("bool")), ("stamp", _name("builtin_interfaces/msg/Time"))])))
    out.update(_service(f"{full}_GetResult", ([], [("goal_id", _name(UUID))]),
                        ([], [("status", _base("int8")), ("result", _name(f"{full}_Result"))])))
    out[full] = ([], [("goal", _name(f"{full}_Goal")), ("result", _name(f"{full}_Result")),
                      ("feedback", _name(f"{full}_Feedback")), ("send_goal_service", _name(f"{full}_SendGoal")),
                      ("get_result_service", _name(f"{full}_GetResult")),
                      ("feedback_message", _name(f"{full}_FeedbackMessage"))])
    return out


def _char_as_uint8(desc: tuple[Any, Any]) -> tuple[Any, Any]:
    """In ROS 2 ``char`` is an alias of ``uint8`` (docs.ros.org "Interfaces", field types) and rosidl describes it
    so; rosbags 0.11 hashes it as its own type, which changes ``service_msgs/msg/ServiceEventInfo`` (its
    ``char[16] client_gid``) and every service event and action using it."""
    def fix(node: tuple[Any, Any]) -> tuple[Any, Any]:
        kind, detail = node
        if kind == Nodetype.BASE and detail[0] == "char":
            return kind, ("uint8", detail[1])
        if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            return kind, (fix(detail[0]), detail[1])
        return node

    consts, fields = desc
    return consts, [(name, fix(node)) for name, node in fields]


def typestore(texts: dict[str, str], store: Stores = Stores.ROS2_JAZZY) -> Any:
    """rosbags' ``store`` with every type of ``texts`` (``pkg/<msg|srv|action>/Name`` -> text) registered."""
    ts = get_typestore(store)
    event_info = "service_msgs/msg/ServiceEventInfo"
    ts.fielddefs[event_info] = _char_as_uint8(ts.fielddefs[event_info])
    types: dict[str, Any] = {}
    for full, text in texts.items():
        kind = full.split("/")[1]
        if kind == "msg":
            types[full] = _parse(text, full)
        elif kind == "srv":
            types.update(srv_types(text, full))
        else:
            types.update(action_types(text, full))
    ts.register(types)
    return ts
