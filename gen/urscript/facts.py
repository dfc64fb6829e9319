r"""URScript facts the URScript backend relies on, each with the page it was read on.

A fact is *confirmed* only when a Universal Robots manual page (Script Manual / Script
Directory, or a UR user manual) states it; the ``source`` is that page. Anything else is
marked unconfirmed and names where the claim came from, so generated comments and the
README can say so.

SD = Universal Robots e-Series Script Directory (PolyScope 5), section and page, read in a
text copy of the manual; SW5.20 etc. = the Script Manual's HTML pages on universal-robots.com.

========================================  =======================================  =========
function / fact                           arguments, units, limits                 confirmed
========================================  =======================================  =========
encoder_get_tick_count(encoder_index,     index 0 or 1; filtered count is a float  yes (SW5.20,
opt="")                                   in [0; 65536[ (wraps at 2^16); opt="raw"  SD 14.4)
                                          gives int32 in [-2^31; 2^31[
encoder_unwind_delta_tick_count(          unwinds a delta larger than half the     yes (SW5.24)
encoder_index, delta_tick_count)          encoder range (heuristic); needs the
                                          range known (UINT16 example)
encoder_enable_pulse_decode(encoder_      index 0 or 1; type 1 quadrature; A, B    yes (SD 14.2,
index, decoder_type, A, B)                input pins 8-11; decodes up to 40 kHz     p. 26)
get_actual_joint_positions()              6 joint angles in rad, [Base, Shoulder,  yes (SW10.10,
                                          Elbow, Wrist1, Wrist2, Wrist3]           via _history)
joint positions q                         lists of 6 floats, one per joint; the    yes (SW10.13,
                                          controller runs at 500 Hz                SW5.25)
movej(q, a=1.4, v=1.05, t=0, r=0)         q rad, a rad/s^2, v rad/s (leading       yes (SD 14.22,
                                          axis), t s, r m                          p. 34)
socket_open(address, port,                True on success, False on failure;       yes (SD 17.55,
socket_name="socket_0")                   times out after 2 s; the robot is the     p. 118)
                                          client
socket_send_line(str, socket_name)        sends str and a newline, ASCII; returns  yes (SD 17.63,
                                          whether it was sent                      p. 123)
socket_close(socket_name)                 closes the connection                    yes (SD 17.53)
textmsg(s1, s2="")                        s1 and s2 concatenated in the log tab    yes (SD 15.57)
popup(s, title, warning, error,           blocking=True suspends the program until yes (SD 15.35)
blocking)                                 Continue is pressed
sleep(t)                                  t in s                                   yes (SD 15.48)
sync()                                    the rest of the 2 ms frame; recommended  yes (SW5.25.1,
                                          beside heavy computation                 Thread sched.)
str_cat(op1, op2), str_len(str)           ints as digits, floats with 6 decimals;  yes (SD 15.51,
                                          at most 1023 characters                  15.54)
floor(f)                                  the largest integer not greater than f   yes (SD 16.9)
time(mode=0)                              struct(sec, nanosec): controller time,   yes (SD 15.49,
                                          monotonic since the controller started   SW5.19)
int / float width                         int 32 bit; float 32 bit                 yes (UR16e
                                                                                   user manual)
script sent to port 30002                 starts with def/sec in column 1, ends    yes (SW10.6)
                                          with end in column 1, lines by \n
get_target_payload(),                     the active payload: mass kg; CoG [CoGx,  yes (SD 15.20,
get_target_payload_cog()                  CoGy, CoGz] m from the tool flange        15.21, p. 57;
                                                                                   e-Series)
set_payload(m, cog)                       the whole active payload; resets the     yes (UR
                                          payload inertia matrix                   article; SD
                                                                                   15.43)
set_target_payload(m, cog, inertia=[0,    m kg; cog m from the tool mount; inertia yes (SD
0, 0, 0, 0, 0], transition_time=0)        kg·m² at the CoG, flange axes; s. Not     15.46, p.
                                          emitted: no page gives its first version 65-66;
                                                                                   SW10.6)
get_target_payload_mass()                 no UR page read has it (SD 15.20's mass  no
                                          getter is get_target_payload())
the payload calls on CB3 (SW 3.x)         get_target_payload(_cog)                 no
halt; int32 overflow in a subtraction                                              no
the same functions on CB3 (SW 3.x)        e.g. pulse-decoder input numbers         no
calibration.conf delta_theta, delta_a,    deltas to the nominal standard DH        no (ROS
delta_d, delta_alpha (m, rad)             table, one per joint; the controller     driver docs)
                                          reports full dh_theta/a/d/alpha
========================================  =======================================  =========

Consequence for the programs: a float holds 24 significant bits, so the filtered count
(< 2^16) is exact, but a sum of many counts or an unwrapped position beyond 2^24 counts is
not; the raw int32 count avoids both (2^31 counts × 0.025488 mm ≫ any wire range), and the
programs turn numbers into text through integers only (``floor``, ``str_cat`` of an int).
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
SD = "Universal Robots e-Series Script Directory (PolyScope 5), "
"""The manual most facts were read in (a text copy of it), cited by section and page."""

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
        "encoder_enable_pulse_decode(encoder_index, decoder_type, A, B): encoder_index 0 or "
        "1; decoder_type 1 = quadrature (A and B square waves 90 degrees apart); A, B the "
        "input pins, 8-11; the controller decodes inputs at up to 40 kHz",
        True,
        SD + "§14.2, p. 26 (text copy); CB3 software not confirmed",
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
        "of the leading axis rad/s^2, v its speed rad/s, t time s, r blend radius m; the "
        "robot must be at a standstill or come from a blended movej/movel",
        True,
        SD + "§14.22, p. 34 (text copy)",
    ),
    Fact(
        "socket_open",
        'socket_open(address, port, socket_name="socket_0"): opens a TCP connection (the '
        "robot is the client); False if failed, True if established; times out after 2 s",
        True,
        SD + "§17.55, p. 118 (text copy)",
    ),
    Fact(
        "socket_send_line",
        'socket_send_line(str, socket_name="socket_0"): sends str and a newline in ASCII; '
        "returns whether the send operation was successful",
        True,
        SD + "§17.63, p. 123 (text copy)",
    ),
    Fact(
        "socket_close",
        'socket_close(socket_name="socket_0"): closes the connection',
        True,
        SD + "§17.53, p. 117 (text copy)",
    ),
    Fact(
        "textmsg",
        'textmsg(s1, s2=""): s1 and s2 concatenated, shown in the PolyScope log tab; other '
        "types can be sent; not meant for many messages at a high rate",
        True,
        SD + "§15.57, p. 73 (text copy)",
    ),
    Fact(
        "popup",
        'popup(s, title="Popup", warning=False, error=False, blocking=False): a message '
        "window; blocking=True suspends the program until Continue is pressed",
        True,
        SD + "§15.35, p. 62 (text copy)",
    ),
    Fact("sleep", "sleep(t): waits t seconds", True, SD + "§15.48, p. 67 (text copy)"),
    Fact(
        "sync",
        "sync() and sleep use 'physical' time: each thread has a 2 ms slice per frame "
        "(500 Hz); inserting sync or sleep next to computationally heavy instructions is "
        "recommended, else 'Lost communication with Controller' and a protective stop. How "
        "many operations fit in one frame is not stated",
        True,
        f"{_UR}/SW5_25_1/Content/prod-scriptmanual/all_scripts/ThreadScheduling.htm",
    ),
    Fact(
        "str_cat",
        "str_cat(op1, op2): the concatenation; an int as its digits, a float with 6 "
        "decimals and trailing zeros removed; at most 1023 characters; str_len(str) the "
        "number of bytes",
        True,
        SD + "§15.51 and §15.54, pp. 69-71 (text copy)",
    ),
    Fact(
        "floor",
        "floor(f): the largest integer not greater than f (returns an integer)",
        True,
        SD + "§16.9, p. 79 (text copy)",
    ),
    Fact(
        "time",
        "time(mode=0): struct(sec, nanosec); mode 0 the controller execution time since the "
        "low-level controller started, guaranteed monotonic",
        True,
        SD + "§15.49, p. 67 (text copy); whether CB3 software has it is not confirmed",
    ),
    Fact(
        "get_target_payload",
        "get_target_payload(): the active payload's mass (kg); get_target_payload_cog(): its "
        "CoG [CoGx, CoGy, CoGz] (m) with respect to the tool flange",
        True,
        SD + "15.20, 15.21, p. 57",
    ),
    Fact(
        "set_payload",
        "set_payload(m, cog): mass kg, CoG [CoGx, CoGy, CoGz] m from the tool mount; resets "
        "the payload inertia matrix; deprecated since SW 5.10.0 for set_target_payload",
        True,
        SD + "15.43, p. 64; Universal Robots article how-to-change-payload-and-center-of-"
        "gravity-settings-using-urscript (CB3 3.3 and every e-Series)",
    ),
    Fact(
        "set_target_payload",
        "set_target_payload(m, cog, inertia=[0, 0, 0, 0, 0, 0], transition_time=0): m kg; cog "
        "[CoGx, CoGy, CoGz] m from the tool mount; inertia [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] "
        "kg·m² at the CoG in the flange's axes (a zero matrix when left out); transition_time "
        "s (0: at once, as set_payload). Not emitted: no page read gives its first version",
        True,
        SD + f"15.46, p. 65-66; {_UR}/SW10_6/Content/prod-scriptmanual/G5/set_target_payload.htm",
    ),
    Fact(
        "get_target_payload_mass",
        "a getter of the active payload's mass by this name: on no Universal Robots page "
        "read (the Script Directory's is get_target_payload(), 15.20)",
        False,
        "not found on a Universal Robots page",
    ),
    Fact(
        "halt",
        "halt ends the program (used after a failed socket_open, behind a blocking popup)",
        False,
        "not read on a manual page",
    ),
    Fact(
        "int32 overflow",
        "how an int subtraction that overflows 32 bits behaves (the raw count is unwrapped "
        "by subtracting the first reading of a point)",
        False,
        "not stated on the pages read",
    ),
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
