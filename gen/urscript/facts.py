r"""URScript facts the URScript backend relies on, each with the page it was read on.

A fact is *confirmed* only when a Universal Robots manual page (Script Manual / Script
Directory, or a UR user manual) states it; the ``source`` is that page. Anything else is
marked unconfirmed and names where the claim came from, so generated comments and the
README can say so.

========================================  =======================================  =========
function / fact                           arguments, units, limits                 confirmed
========================================  =======================================  =========
encoder_get_tick_count(encoder_index,     index 0 or 1; filtered count is a float  yes (SW5.20)
opt="")                                   in [0; 65536[ (wraps at 2^16); opt="raw"
                                          gives int32 in [-2^31; 2^31[
encoder_unwind_delta_tick_count(          unwinds a delta larger than half the     yes (SW5.24)
encoder_index, delta_tick_count)          encoder range (heuristic); needs the
                                          range known (UINT16 example)
encoder_enable_pulse_decode(...)          quadrature decoding on digital inputs;   no
                                          argument list and the ~40 kHz limit are
                                          from the issue text only
get_actual_joint_positions()              6 joint angles in rad, [Base, Shoulder,  yes (SW10.10,
                                          Elbow, Wrist1, Wrist2, Wrist3]           via _history)
joint positions q                         lists of 6 floats, one per joint; the    yes (SW10.13,
                                          controller runs at 500 Hz                SW5.25)
movej(q, a=1.4, v=1.05, t=0, r=0)         q rad, a rad/s^2, v rad/s, t s, r m      no (3rd-party)
socket_open(address, port,                returns True/False; times out after 2 s  no (3rd-party)
socket_name="socket_0")                   the robot is the client
socket_send_line(str, socket_name)        sends the string and a newline           no
textmsg(s1, s2="")                        writes to the controller log             no
sleep(t)                                  t in s                                   no
int / float width                         int 32 bit; float 32 bit                 yes (UR16e
                                                                                   user manual)
script sent to port 30002                 starts with def/sec in column 1, ends    yes (SW10.6)
                                          with end in column 1, lines by \n
calibration.conf delta_theta, delta_a,    deltas to the nominal standard DH        no (ROS
delta_d, delta_alpha (m, rad)             table, one per joint; the controller     driver docs)
                                          reports full dh_theta/a/d/alpha
========================================  =======================================  =========

Consequence for the programs: a float holds 24 significant bits, so the filtered count
(< 2^16) is exact, but a sum of many counts or an unwrapped position beyond 2^24 counts is
not; the raw int32 count avoids both (2^31 counts × 0.025488 mm ≫ any wire range).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Fact:
    """One URScript fact: what it is, its arguments/units/limits, and where it was read."""

    name: str
    detail: str
    confirmed: bool
    source: str


_UR = "https://www.universal-robots.com/manuals/EN/HTML"

FACTS: tuple[Fact, ...] = (
    Fact(
        "encoder_get_tick_count",
        'encoder_get_tick_count(encoder_index, opt=""): encoder_index 0 or 1; returns the '
        'filtered tick count (float) in [0; 65536[, which wraps; opt="raw" returns the raw '
        "int32 count in [-2^31; 2^31[",
        True,
        f"{_UR}/SW5_20/Content/prod-scriptmanual/G5/encoder_get_tick_count_encoder_index.htm",
    ),
    Fact(
        "encoder_unwind_delta_tick_count",
        "encoder_unwind_delta_tick_count(encoder_index, delta_tick_count): a delta larger "
        "than half the encoder range is taken as a wrap and unwound; the range must be known",
        True,
        f"{_UR}/SW5_24/Content/prod-scriptmanual/all_scripts/encoder_unwind_delta_tick_count.htm",
    ),
    Fact(
        "encoder_enable_pulse_decode",
        "enables quadrature decoding of an encoder on the controller's digital inputs; "
        "argument list and the ~40 kHz limit not read on a UR page",
        False,
        "issue text only (no manual page found)",
    ),
    Fact(
        "get_actual_joint_positions",
        "returns the joint angular positions in rad: [Base, Shoulder, Elbow, Wrist1, Wrist2, "
        "Wrist3] (stated on the page of get_actual_joint_positions_history)",
        True,
        f"{_UR}/SW10_10/Content/prod-scriptmanual/all_scripts/get_actual_jo_pos_his.htm",
    ),
    Fact(
        "joint positions",
        "joint positions q are lists of 6 floats, one per joint; the runtime machine talks "
        "to the robot at 500 Hz",
        True,
        f"{_UR}/SW10_13/Content/prod-scriptmanual/all_scripts/Module_otion.htm",
    ),
    Fact(
        "movej",
        "movej(q, a=1.4, v=1.05, t=0, r=0): q joint positions in rad, a joint acceleration "
        "rad/s^2, v joint speed rad/s, t time s, r blend radius m",
        False,
        "third-party pages only (e.g. https://vnrobo.com/en/blog/trad-manip-3-movej-movel)",
    ),
    Fact(
        "socket_open",
        'socket_open(address, port, socket_name="socket_0"): the robot is the client; '
        "returns True on success, False on failure; gives up after 2 s",
        False,
        "third-party page only (https://blog.csdn.net/weixin_52531852/article/details/124178707)",
    ),
    Fact(
        "socket_send_line",
        'socket_send_line(str, socket_name="socket_0"): sends the string and a newline',
        False,
        "no manual page found",
    ),
    Fact("textmsg", 'textmsg(s1, s2=""): writes to the controller log', False, "no page found"),
    Fact("sleep", "sleep(t): waits t seconds", False, "no manual page found"),
    Fact(
        "number widths",
        "int: 32-bit whole number (-2147483648..2147483647); float: 32-bit floating point",
        True,
        "UR16e User Manual p. 181, Variable Value Types "
        "(copy at https://www.easymanua.ls/universal-robots/ur16e/manual?p=181)",
    ),
    Fact(
        "script over port 30002",
        "a script starts with def or sec in the first column, other lines indented, the "
        "last line end in the first column; lines end with \\n; extended ASCII only",
        True,
        f"{_UR}/SW10_6/Content/prod-scriptmanual/G5/Connecting_to_URControl.htm",
    ),
    Fact(
        "calibration.conf",
        "the controller holds its factory calibration as full standard-DH values per joint "
        "(dh_theta, dh_a, dh_d, dh_alpha; m, rad), with d of joints 2 and 3 up to hundreds "
        "of metres (true common normals of nearly parallel axes); the delta_* key names "
        "and the file layout are not published by UR",
        False,
        "ROS driver docs only "
        "(https://docs.ros.org/en/humble/p/ur_calibration/_sources/doc/algorithm.rst.txt)",
    ),
)


def fact(name: str) -> Fact:
    """Return the fact called ``name``; ``KeyError`` names the known ones."""
    for f in FACTS:
        if f.name == name:
            return f
    raise KeyError(f"no URScript fact {name!r}; known: {', '.join(f.name for f in FACTS)}")
