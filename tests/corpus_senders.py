"""How the senders of the corpus's URScript programs fill them in before sending.

Written from the senders' public source (not copied): ur_rtde ``src/script_client.cpp``
(``removeUnsupportedFunctions``, ``scanAndInjectAdditionalScriptCode``, ``sendScript``;
the injections of ``src/rtde_control_interface.cpp``) and Universal Robots' client library
``src/control/script_reader.cpp`` (``replaceVariables``, ``replaceConditionals``) with
``src/ur/ur_driver.cpp`` (the values it fills in; headless mode's ``def externalControl():``
wrapper, each line behind a tab).
"""

from __future__ import annotations

import re

URCL_VALUES = {
    "BEGIN_REPLACE": "",
    "JOINT_STATE_REPLACE": 1000000,  # ReverseInterface::MULT_JOINTSTATE
    "TIME_REPLACE": 1000000,  # TrajectoryPointInterface::MULT_TIME
    "SERVO_J_REPLACE": "lookahead_time=0.03, gain=2000",
    "SERVER_IP_REPLACE": "192.168.56.1",
    "SERVER_PORT_REPLACE": 50001,
    "TRAJECTORY_SERVER_PORT_REPLACE": 50003,
    "SCRIPT_COMMAND_SERVER_PORT_REPLACE": 50004,
}
"""What ur_driver.cpp fills in (the ports and address: its defaults for an example PC)."""


def _stoi(text: str) -> int:
    """C++ ``std::stoi``: the leading whole number of ``text``."""
    m = re.match(r"\s*(\d+)", text)
    if m is None:
        raise ValueError(f"no number in {text!r}")
    return int(m.group(1))


def ur_rtde_sent(script: str, software: str, offset: int = 0) -> str:
    """Return ur_rtde's ``rtde_control.script`` as it sends it to a controller of ``software``.

    A line marked ``$M.mm`` (or ``$M.mm|C.cc``, a CB3 version too) is kept, its mark blanked,
    when the controller is at least that version, and dropped otherwise; the register
    offset (0, or 24 for the upper registers) goes right after each offset comment's line.
    """
    major, minor = (int(x) for x in software.split(".")[:2])
    text = "def rtde_control():\n" + script + "end\n"
    n = text.find("$")
    while n != -1:
        v = text[n + 1 : n + 10]
        need = (_stoi(v[0]), _stoi(v[2:6]))
        extra = (_stoi(v[5]), _stoi(v[7:9])) if v[4] == "|" else (0, 0)
        if (major, minor) >= need or (major == extra[0] and minor >= extra[1]):
            width = 10 if v[4] == "|" else 5
            text = text[:n] + " " * width + text[n + width :]
        else:
            text = text[:n] + text[text.find("\n", n) + 1 :]
        n = text.find("$")
    for marker in ("# float register offset\n", "# int register offset\n"):
        k = text.find(marker)
        if k != -1:
            text = text[: k + len(marker)] + str(offset) + text[k + len(marker) :]
    return text


_DIRECTIVE = re.compile(r"\{%\s*(if|elif|else|endif)\s*(.*?)\s*%\}")


def _version(text: str) -> tuple[int, ...]:
    return tuple(int(x) for x in text.lstrip("v").split("."))


def _holds(condition: str, values: dict[str, object]) -> bool:
    """A condition of the form ``NAME OP vX.Y.Z``."""
    name, op, value = condition.split()
    a, b = _version(str(values[name])), _version(value)
    return {"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b, "==": a == b, "!=": a != b}[op]


def urcl_sent(script: str, software: str) -> str:
    """Return the client library's ``external_control.urscript`` filled in for ``software``."""
    values: dict[str, object] = {**URCL_VALUES, "ROBOT_SOFTWARE_VERSION": software}
    script = re.sub(r"\{\{\s*([\w-]+)\s*\}\}", lambda m: str(values[m.group(1)]), script)
    out: list[str] = []
    stack: list[tuple[bool, bool]] = []  # (this branch is kept, a branch was taken)
    for line in script.split("\n"):
        m = _DIRECTIVE.search(line)
        if m is None:
            if all(kept for kept, _ in stack):
                out.append(line)
            continue
        kind, condition = m.groups()
        if kind == "endif":
            stack.pop()
            continue
        taken = stack.pop()[1] if kind != "if" else False
        parent = all(kept for kept, _ in stack)
        holds = kind == "else" or _holds(condition, values)
        keep = parent and not taken and holds
        stack.append((keep, taken or keep))
    return "def externalControl():\n" + "".join(f"\t{line}\n" for line in out) + "end\n"


def sent(send: str, text: str, software: str | None) -> list[tuple[str, str | tuple[str, str]]]:
    """Return (label, text) of each form the sender ``send`` sends ``text`` in.

    A text is a whole program, or (program, fragment): a program with a file included.
    """
    if send == "ur_rtde":
        assert software is not None
        return [(f"{software}, offset {k}", ur_rtde_sent(text, software, k)) for k in (0, 24)]
    if send == "urcl":
        assert software is not None
        return [(software, urcl_sent(text, software))]
    if send == "python-string":  # a script kept in a Python '''…''' string
        quotes = "'" * 3
        body = text.split(quotes, 1)[1].rsplit(quotes, 1)[0]
        main = 'def main():\n  textmsg("main")\nend\n'
        return [("in a program", f"def program():\n{body}\nend\n"), ("included", (main, body))]
    assert send == "as-is", send
    return [("as loaded", text)]
