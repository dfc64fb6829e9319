r"""What wirecal's RAPID checker knows: data types, predefined data, instructions, functions.

Each instruction and function carries the page its signature comes from (``source``) and the
RobotWare version it needs (``since``). Pages read (stored public copies; ABB's own
PDFs were not reachable, so the reading was of copies and translations):

* ``kernel-types``: RAPID kernel manual, "Built-in data types" (num: IEEE 754, exact integers
  in -8388607..8388608; dnum: exact integers in ±4503599627370496; string: 0 to 80
  characters), read in a translation, blog.csdn.net/m0_47707298/article/details/115558461;
* ``MoveAbsJ``: RAPID reference manual, instructions, MoveAbsJ (syntax ``MoveAbsJ [\Conc]
  ToJointPos [\ID] [\NoEOffs] Speed [\V]|[\T] Zone [\Z] [\Inpos] Tool [\WObj]`` and
  its arguments), read in translations at 360docs.net/doc/7114964515.html and
  abbjqr.gbsrobot.com/news/index.php?itemid=24292;
* ``loaddata``: :data:`LOADDATA_PAGE` (an older RAPID Reference Manual, p. 183), with
  ``GripLoad`` as a controller-loaded program uses it (:data:`GRIPLOAD_LOADED`);
* ``tooldata``: :data:`TOOLDATA_PAGE` (the same manual, pp. 225–227).

Everything else below is marked "unconfirmed": written from the 3HAC050917 manual's
structure as wirecal's authors know it, not from a page read for this table. ``since`` is
"6.0" (wirecal's floor: RobotWare 6, IRC5) unless a page said otherwise; when each
instruction first appeared is unconfirmed.
"""

from __future__ import annotations

from dataclasses import dataclass

NUM_EXACT = (-8388607, 8388608)
"""The integers a num holds exactly (kernel-types: "-8388607 to (+)8388608")."""

DNUM_EXACT = (-4503599627370496, 4503599627370496)
"""The integers a dnum holds exactly (kernel-types)."""

STRING_MAX = 80
"""The most characters a string holds (kernel-types: "0 to 80 characters")."""

NAME_MAX = 32
"""The longest identifier (RAPID kernel, "Identifiers": unconfirmed, no page read)."""

RESERVED = frozenset(
    """ALIAS AND BACKWARD CASE CONNECT CONST DEFAULT DIV DO ELSE ELSEIF ENDFOR ENDFUNC ENDIF
    ENDMODULE ENDPROC ENDRECORD ENDTEST ENDTRAP ENDWHILE ERROR EXIT FALSE FOR FROM FUNC GOTO
    IF INOUT LOCAL MOD MODULE NOSTEPIN NOT NOVIEW OR PERS PROC RAISE READONLY RECORD RETRY
    RETURN STEP SYSMODULE TEST THEN TO TRAP TRUE TRYNEXT UNDO VAR VIEWONLY WHILE WITH
    XOR""".split()
)
"""RAPID's reserved words (RAPID kernel, "Reserved words": unconfirmed — the list as
wirecal's authors know it; a scanned copy of 3HAC16585-1 was found but not read)."""

MODULE_ATTRIBUTES = frozenset({"SYSMODULE", "NOVIEW", "NOSTEPIN", "VIEWONLY", "READONLY"})
"""Module attributes (RAPID kernel, "Module declarations": unconfirmed)."""

RECORDS: dict[str, tuple[tuple[str, str], ...]] = {
    "robjoint": tuple((f"rax_{i}", "num") for i in range(1, 7)),
    "extjoint": tuple((f"eax_{c}", "num") for c in "abcdef"),
    "jointtarget": (("robax", "robjoint"), ("extax", "extjoint")),
    "speeddata": (("v_tcp", "num"), ("v_ori", "num"), ("v_leax", "num"), ("v_reax", "num")),
    "pos": (("x", "num"), ("y", "num"), ("z", "num")),
    "orient": (("q1", "num"), ("q2", "num"), ("q3", "num"), ("q4", "num")),
    "pose": (("trans", "pos"), ("rot", "orient")),
    "loaddata": (
        ("mass", "num"),
        ("cog", "pos"),
        ("aom", "orient"),
        ("ix", "num"),
        ("iy", "num"),
        ("iz", "num"),
    ),
    "tooldata": (("robhold", "bool"), ("tframe", "pose"), ("tload", "loaddata")),
}
"""The record types of the subset and their components (reference manual, data types
jointtarget, robjoint, extjoint, speeddata, pos: unconfirmed; loaddata's mass (num, kg), cog
(pos, mm) and aom (orient, a quaternion): :data:`LOADDATA_PAGE`; its ix, iy, iz (num, the
moments of inertia about the axes of moment, kgm^2): unconfirmed — the RAPID manual's names
as ROS-Industrial's abb_rapid_msgs LoadData.msg repeats them, not read on an ABB page;
tooldata's robhold (bool), tframe (pose: trans, a pos in mm, and rot, a quaternion) and
tload (loaddata): :data:`TOOLDATA_PAGE`; pose's component names trans and rot: tool0's
value there is written as their aggregate, the names themselves unconfirmed)."""

LOADDATA_PAGE = (
    "RAPID Reference Manual (yumpu.com/en/document/view/5679047), p. 183, loaddata: "
    "mass in kg, cog in mm in the tool coordinate system for a payload, aom a quaternion; "
    "the payload connected and disconnected with GripLoad; load data lighter or heavier "
    "than the true load impairs path accuracy, with a risk of overshooting"
)
"""The page read for loaddata and GripLoad's use."""

TOOLDATA_PAGE = (
    "RAPID Reference Manual (yumpu.com/en/document/view/5679047), pp. 225-227, tooldata: "
    "robhold TRUE, the robot holds the tool; tframe the TCP in the wrist coordinate system "
    "(tool0's: the centre of the mounting flange); tload the tool's own load, the payload "
    "connected and disconnected with GripLoad; an incorrect load can cause overshooting; "
    "a tool in a motion instruction only an entire persistent"
)
"""The page read for tooldata (components, tool0's value, the Tool argument's rule)."""

GRIPLOAD_LOADED = (
    "GripLoad of a loaddata built at run time loaded by an IRC5 controller: "
    "EdgarIvanMM/PaletizadoCajasConFrascos@850dc0e RAPID/TASK1/PROGMOD/MainModule.mod "
    "lines 67, 170-171"
)
"""A controller-loaded program using GripLoad as wirecal's module does (GripLoad's own page:
unconfirmed, not read)."""

ATOMIC = frozenset({"num", "dnum", "bool", "string"})
"""The atomic types (kernel-types)."""

OPAQUE = frozenset({"iodev", "clock", "signalgi"})
"""Non-value types of the subset: a file (iodev), a clock and a group input bound with
AliasIO (reference manual: unconfirmed)."""

SUBSET_TYPES = ATOMIC | OPAQUE | frozenset(RECORDS)
"""The data types a wirecal module may declare."""

OTHER_TYPES = frozenset(
    """robtarget confdata wobjdata zonedata stoppointdata
    intnum errnum signaldi signaldo signalgo signalai signalao byte rawbytes
    socketdev socketstatus triggdata tpnum dir switch egmident mecunit errdomain errstr
    identno shapedata wzstestablished syncident tasks progdisp""".split()
)
"""RAPID data types outside the subset (a declaration of one is "not in the subset")."""

SUBSET_ERRORS = ("errno", "err_divzero", "err_fileopen", "err_fileacc", "err_aliasio_def")
"""ERRNO and the error numbers an ERROR handler of wirecal's module compares it with:
division by zero, a file that cannot be opened or written, AliasIO's signal not defined
(RAPID reference manual, error recovery and AliasIO: unconfirmed, no page read)."""

SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000)
SPEEDS_FAST = (1500, 2000, 2500, 3000, 4000, 5000, 6000, 7000)
ZONES = (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)

PREDEFINED: dict[str, str] = {
    **{f"v{v}": "speeddata" for v in SPEEDS + SPEEDS_FAST},
    "vmax": "speeddata",
    "fine": "zonedata",
    **{f"z{z}": "zonedata" for z in ZONES},
    "tool0": "tooldata",
    "load0": "loaddata",
    "pi": "num",
    "wobj0": "wobjdata",
    **{k: "num" for k in SUBSET_ERRORS},
}
"""Predefined data the subset reads, name → type (reference manual, speeddata and zonedata
"Predefined data": unconfirmed; tool0, the flange with no tool load: :data:`TOOLDATA_PAGE`;
loaddata load0 (no payload): unconfirmed — load0 is used so in controller-loaded programs,
EdgarIvanMM/PaletizadoCajasConFrascos@850dc0e; pi: ROS-Industrial's abb_driver modules use
it undeclared, its value 3.1415926 is unconfirmed; ERRNO and the errors of
:data:`SUBSET_ERRORS`, errnum, a num alias)."""


OTHER_DATA_PREFIXES = (
    "err_",
    "socket_",
    "io_",
    "diskhome",
    "errno",
    "intno",
    "rob_id",
    "wait_max",
)
"""Name prefixes of RAPID's predefined data outside the subset (ERRNO, ERR_…, SOCKET_… …;
reference manual, errnum and socketstatus: unconfirmed)."""


def other_data(name: str) -> bool:
    """Return whether ``name`` is RAPID's predefined data outside the subset."""
    return name.lower().startswith(OTHER_DATA_PREFIXES)


def speed_values(name: str) -> tuple[float, float, float, float]:
    """Return a predefined speeddata's (v_tcp, v_ori, v_leax, v_reax).

    v_ori 500 deg/s, v_leax 5000 mm/s, v_reax 1000 deg/s for every one (reference manual,
    speeddata, "Predefined data": unconfirmed); vmax's v_tcp (robot dependent) is taken as
    7000 mm/s (unconfirmed).
    """
    v_tcp = 7000.0 if name.lower() == "vmax" else float(name[1:])
    return (v_tcp, 500.0, 5000.0, 1000.0)


@dataclass(frozen=True)
class P:
    r"""One parameter of a routine.

    Its name, type, whether it is optional (``\Name``), and ``var`` for one that must be
    a variable the routine writes (INOUT, or a VAR parameter such as TPReadNum's Answer).
    """

    name: str
    type: str
    optional: bool = False
    var: bool = False
    dims: int = 0  # an array parameter's dimensions ({*}: 1, {*,*}: 2)


@dataclass(frozen=True)
class Routine:
    """A predefined instruction (``returns`` None) or function: parameters, where read."""

    params: tuple[P, ...]
    returns: str | None = None
    source: str = "unconfirmed"
    since: str = "6.0"


_U = "unconfirmed (3HAC050917 page not read)"

INSTRUCTIONS: dict[str, Routine] = {
    "moveabsj": Routine(
        (
            P("Conc", "switch", True),
            P("ToJointPos", "jointtarget"),
            P("NoEOffs", "switch", True),
            P("Speed", "speeddata"),
            P("V", "num", True),
            P("T", "num", True),
            P("Zone", "zonedata"),
            P("Z", "num", True),
            P("Tool", "tooldata"),
            P("WObj", "wobjdata", True),
        ),
        source="MoveAbsJ",
    ),
    "waittime": Routine((P("InPos", "switch", True), P("Time", "num")), source=_U),
    "tpwrite": Routine(
        (
            P("String", "string"),
            P("Num", "num", True),
            P("Bool", "bool", True),
            P("Dnum", "dnum", True),
        ),
        source=_U,
    ),
    "tpreadnum": Routine((P("Answer", "num", var=True), P("TPText", "string")), source=_U),
    "tperase": Routine((), source=_U),
    "open": Routine(
        (
            P("Object", "string"),
            P("File", "string", True),
            P("IODevice", "iodev", var=True),
            P("Read", "switch", True),
            P("Write", "switch", True),
            P("Append", "switch", True),
            P("Bin", "switch", True),
        ),
        source=_U,
    ),
    "write": Routine(
        (
            P("IODevice", "iodev", var=True),
            P("String", "string"),
            P("Num", "num", True),
            P("Bool", "bool", True),
            P("Dnum", "dnum", True),
            P("NoNewLine", "switch", True),
        ),
        source=_U,
    ),
    "close": Routine((P("IODevice", "iodev", var=True),), source=_U),
    "aliasio": Routine((P("FromSignal", "string"), P("ToSignal", "signalgi", var=True)), source=_U),
    "clkreset": Routine((P("Clock", "clock", var=True),), source=_U),
    "clkstart": Routine((P("Clock", "clock", var=True),), source=_U),
    "clkstop": Routine((P("Clock", "clock", var=True),), source=_U),
    "incr": Routine((P("Name", "num", var=True),), source=_U),
    "decr": Routine((P("Name", "num", var=True),), source=_U),
    "stop": Routine((P("NoRegain", "switch", True),), source=_U),
    "gripload": Routine((P("Load", "loaddata"),), source=f"{LOADDATA_PAGE}; {GRIPLOAD_LOADED}"),
}
"""The instructions of the subset, lower-case name → signature."""


def _f(params: tuple[P, ...], returns: str, source: str = _U) -> Routine:
    return Routine(params, returns, source)


_NUM1 = (P("Value", "num"),)
_DNUM1 = (P("Value", "dnum"),)

FUNCTIONS: dict[str, Routine] = {
    "present": _f((P("OptPar", "optional parameter"),), "bool"),
    "ginputdnum": _f((P("Signal", "signalgi"),), "dnum"),
    "ginput": _f((P("Signal", "signalgi"),), "num"),
    "clkread": _f((P("Clock", "clock", var=True), P("HighRes", "switch", True)), "num"),
    "cjointt": _f((P("TaskRef", "num", True), P("TaskName", "string", True)), "jointtarget"),
    "sqrt": _f(_NUM1, "num"),
    "sqrtdnum": _f(_DNUM1, "dnum"),
    "abs": _f(_NUM1, "num"),
    "absdnum": _f(_DNUM1, "dnum"),
    "round": _f((P("Val", "num"), P("Dec", "num", True)), "num"),
    "rounddnum": _f((P("Val", "dnum"), P("Dec", "num", True)), "dnum"),
    "trunc": _f((P("Val", "num"), P("Dec", "num", True)), "num"),
    "truncdnum": _f((P("Val", "dnum"), P("Dec", "num", True)), "dnum"),
    "numtostr": _f((P("Val", "num"), P("Dec", "num"), P("Exp", "switch", True)), "string"),
    "dnumtostr": _f((P("Val", "dnum"), P("Dec", "num"), P("Exp", "switch", True)), "string"),
    "numtodnum": _f(_NUM1, "dnum"),
    "dnumtonum": _f((P("Value", "dnum"), P("Integer", "switch", True)), "num"),
    "strlen": _f((P("Str", "string"),), "num"),
    "sin": _f((P("Angle", "num"),), "num"),
    "cos": _f((P("Angle", "num"),), "num"),
    "tan": _f((P("Angle", "num"),), "num"),
    "asin": _f(_NUM1, "num"),
    "acos": _f(_NUM1, "num"),
    "atan": _f(_NUM1, "num"),
    "atan2": _f((P("Y", "num"), P("X", "num")), "num"),
    "exp": _f((P("Exponent", "num"),), "num"),
    "pow": _f((P("Base", "num"), P("Exponent", "num")), "num"),
}
"""The functions of the subset, lower-case name → signature."""

_CONTROLLER_LOADED = """GetDataVal SetDataVal IsFile MakeDir RemoveFile RemoveDir OpenDir
    CloseDir ReadDir RenameFile CopyFile FileSize FSSize RemainingRetries RobOS UIMessageBox
    UIListView UIClientExist UIAlphaEntry UINumTune DotProd VectMagn CrossProd EGMGetId
    EGMSetupUC EGMSetupAI EGMSetupAO EGMSetupGI EGMActJoint EGMActPose EGMRunJoint EGMRunPose
    EGMStop EGMReset EGMStreamStart EGMStreamStop EGMGetState EOffsSet EOffsOn EOffsOff PDispOn
    PDispOff PDispSet WZFree WZEnable WZDisable WZDOSet WZBoxDef WZCylDef WZSphDef WZLimSup
    BitCheckDnum BitAndDnum BitOrDnum GInputDnum GOutputDnum SetGODnum GInput AInput TPWrite
    ReadErrData ResetRetryCount StartMoveRetry StopMoveReset CJointT CalcJointT IsMechUnitActive
    ActUnit DeactUnit TriggIO TriggEquip TriggInt MToolRotCalc MToolTCPCalc CSpeedOverride
    SetAllDataVal SetSysData GetMecUnitName GetNextSym SetDataSearch ReadVar WriteVar StrLen
    Abs Round Trunc Sqrt Sin Cos Tan ATan2 ACos ASin Exp Pow NumToDnum DnumToNum ClkRead
    ClkReset ClkStart ClkStop"""
"""RAPID routines that public, controller-loaded programs call and wirecal reads without a
signature (their arguments are read, not matched): the COMPAS RRC controller modules
(compas-rrc/compas_rrc_start@4b831ac, an IRC5 RobotWare 6 backup), the IRC5 backups
SDEBEUL/Kraker1@5a5835c and EdgarIvanMM/PaletizadoCajasConFrascos@850dc0e. Each exists in
the 3HAC050917 reference manual as wirecal's authors know it: unconfirmed, no page read.
Routines with a signature in the tables above keep it (this set subtracts them)."""

OTHER_ROUTINES = frozenset(
    name.lower()
    for name in """MoveJ MoveL MoveC MoveJDO MoveLDO MoveCDO MoveJSync MoveLSync MoveExtJ
    SearchL SearchC TriggL TriggJ TriggC StopMove StartMove ConfJ ConfL SingArea AccSet VelSet
    PathAccLim SetDO SetGO SetAO Set Reset PulseDO InvertDO WaitDI WaitDO WaitGI WaitAI
    WaitUntil WaitRob WaitSyncTask SyncMoveOn SyncMoveOff GripLoad ErrWrite ErrLog TPReadFK
    TPShow UIMsgBox UINumEntry SocketCreate SocketConnect SocketSend SocketReceive SocketClose
    SocketBind SocketListen SocketAccept ISignalDI ISignalDO ITimer IDelete IEnable IDisable
    ISleep IWatch Load UnLoad StartLoad WaitLoad EraseModule WriteStrBin WriteBin ReadAnyBin
    Add Clear Rewind ClearPath StorePath RestoPath Break ProcCall CallByVar SetSysData
    Offs RelTool CRobT CPos CTool CWObj DInput DOutput GOutput GOutputDnum AInput AOutput
    StrToVal ValToStr StrFind StrPart StrMap StrMatch StrMemb StrOrder ReadNum ReadStr ReadBin
    OpMode RunMode IsPers IsVar Present Dim GetTime CTime CDate EulerZYX OrientZYX PoseInv
    PoseMult PoseVect NOrient CalcJointT CalcRobT MaxRobSpeed GetNextMechUnit IsStopStateEvent
    ArgName Type TestDI TestSignRead NumToStr ClkWait SocketGetStatus GetSysInfo SkipWarn
    TestAndSet WaitTestAndSet ErrRaise IsSysId GetTaskName RMQSendMessage RMQGetMessage
    ReadRawBytes WriteRawBytes PackRawBytes UnpackRawBytes CopyRawBytes ClearRawBytes
    RawBytesLen StrToByte ByteToStr BitCheck BitSet BitClear BitAnd BitOr BitXOr BitNeg
    BitLSh BitRSh ReadCfgData WriteCfgData IPers ExitCycle IsStopMoveAct""".split()
) | frozenset(name.lower() for name in _CONTROLLER_LOADED.split()) - frozenset(
    FUNCTIONS
) - frozenset(INSTRUCTIONS)
"""RAPID instructions and functions outside the subset (a call is "not in the subset")."""


# --- RAPID beyond the twin's subset: what the checker reads in others' programs -----------
#
# Pages read for these (stored public copies):
#
# * ``RM``: "RAPID Reference Manual" (an S4C-era edition: "Basic Characteristics RAPID"),
#   yumpu.com/en/document/view/5679047 — page 211-212 robtarget (trans pos, rot orient,
#   robconf confdata, extax extjoint), 385-386 RAISE ("RAISE [Error no.]", errnum, "must be
#   specified outside the error handler"), 51 and 112 interrupts (CONNECT … WITH, intnum,
#   ISignalDI, IDelete, TRAP … ENDTRAP, RETURN in a trap routine);
# * ``MoveJ``: "MoveJ [\Conc,] ToPoint, Speed [\V]|[\T], Zone [\Z] [\Inpos], Tool [\WObj]",
#   blog.csdn.net/weixin_42126274/article/details/111886431 (a translation of the manual);
# * ``zonedata``: ABB's PC SDK, ZoneData structure (FineP, pZoneTcp, pZoneOri, pZoneEax,
#   ZoneOri, ZoneLeax, ZoneReax), developercenter.robotstudio.com/api/fpsdk.
#
# Every other row is "unconfirmed": written from the 3HAC050917 manual's structure as
# wirecal's authors know it.

_RM = "RAPID Reference Manual (yumpu.com/en/document/view/5679047)"
RM_RAISE = f"{_RM}, p. 385: the error number must be given outside the error handler"
_MOVEJ = "MoveJ (blog.csdn.net/weixin_42126274/article/details/111886431)"

WIDE_RECORDS: dict[str, tuple[tuple[str, str], ...]] = {
    "tasks": (("taskname", "string"),),
    "listitem": (("image", "string"), ("text", "string")),
    "egm_minmax": (("min", "num"), ("max", "num")),
    "confdata": (("cf1", "num"), ("cf4", "num"), ("cf6", "num"), ("cfx", "num")),
    "robtarget": (
        ("trans", "pos"),
        ("rot", "orient"),
        ("robconf", "confdata"),
        ("extax", "extjoint"),
    ),
    "wobjdata": (
        ("robhold", "bool"),
        ("ufprog", "bool"),
        ("ufmec", "string"),
        ("uframe", "pose"),
        ("oframe", "pose"),
    ),
    "zonedata": (
        ("finep", "bool"),
        ("pzone_tcp", "num"),
        ("pzone_ori", "num"),
        ("pzone_eax", "num"),
        ("zone_ori", "num"),
        ("zone_leax", "num"),
        ("zone_reax", "num"),
    ),
}
"""Record types beyond the subset (robtarget: RM p. 211; zonedata: the PC SDK's ZoneData;
confdata, wobjdata: unconfirmed; pos, orient, pose, loaddata, tooldata are the subset's)."""

ALIASES: dict[str, str] = {
    "errnum": "num",
    "intnum": "num",
    "dionum": "num",
    "socketstatus": "num",
    "symnum": "num",
    "byte": "num",
    "tpnum": "num",
    "inttypes": "num",
    "errstr": "string",
    "btnres": "num",
    "buttondata": "num",
    "icondata": "num",
}
"""Alias types and the type each names (RM: RAISE's argument is an errnum and ERRNO is
compared with numbers; the others unconfirmed — btnres, buttondata and icondata as the COMPAS
RRC and Kraker1 modules use them with UIMessageBox and WaitUntil \\Icon)."""

WIDE_OPAQUE = frozenset(
    """socketdev rawbytes signaldi signaldo signalgi signalgo signalai signalao triggdata
    dir mecunit wzstationary wztemporary shapedata syncident identno stoppointdata
    errdomain egmident progdisp""".split()
)
"""Non-value types beyond the subset: declared, passed, not built from literals
(unconfirmed)."""

SIGNAL_TYPES: dict[str, str] = {
    "signaldi": "a digital input",
    "signaldo": "a digital output",
    "signalgi": "a group input",
    "signalgo": "a group output",
    "signalai": "an analog input",
    "signalao": "an analog output",
}
"""I/O signal types and what each is: an argument may name a signal of the controller's
configuration, not declared in the module (unconfirmed)."""

WIDE_PREDEFINED: dict[str, str] = {
    "errno": "errnum",
    "intno": "intnum",
    "wait_max": "num",
    "high": "dionum",
    "low": "dionum",
    "edge": "dionum",
    "on": "dionum",
    "off": "dionum",
    "z0": "zonedata",
    **{k: "inttypes" for k in ("sint", "int", "dint", "lint", "usint", "uint", "udint", "ulint")},
    **{k: "symnum" for k in ("op_undef", "op_auto", "op_man_prog", "op_man_test")},
    **{k: "symnum" for k in ("run_undef", "run_cont_cycle", "run_instr_fwd", "run_instr_bwd")},
    **{k: "symnum" for k in ("run_sim", "run_step_move")},
    **{k: "stoppointdata" for k in ("inpos20", "inpos50", "inpos100")},
    **{k: "string" for k in ("diskhome", "diskram", "disktemp")},
    **{k: "num" for k in ("eof_bin", "eof_num")},
    **{k: "icondata" for k in ("iconnone", "iconinfo", "iconwarning", "iconerror")},
    **{
        k: "btnres"
        for k in "resunkwn resok resabort resretry resignore rescancel resyes resno".split()
    },
    **{
        k: "buttondata"
        for k in "btnnone btnok btnabrtrtryign btnokcancel btnretrycancel btnyesno".split()
    },
    "btnyesnocancel": "buttondata",
}
"""Predefined data beyond the subset (ERRNO: RM p. 385; INTNO: RM p. 112; inpos50: the
MoveJ page's example ``\\Inpos:=inpos50``; the others unconfirmed). Names starting ERR_
are errnum constants and SOCKET_ socketstatus ones (:func:`wide_data`)."""


SIGNAL_NAME = "signal name"
"""A parameter taking any I/O signal: its name in the configuration, a string holding the
name, or a signal variable (AliasIO's)."""


def wide_data(name: str) -> str | None:
    """Return the type of RAPID's predefined data ``name`` beyond the subset, or None."""
    key = name.lower()
    if key in WIDE_PREDEFINED:
        return WIDE_PREDEFINED[key]
    if key.startswith("err_"):
        return "errnum"
    if key.startswith("socket_"):
        return "socketstatus"
    return None


def _r(*params: P, returns: str | None = None, source: str = _U) -> Routine:
    return Routine(params, returns, source)


def _o(name: str, type_: str = "switch", var: bool = False) -> P:
    return P(name, type_, True, var)


_MOVE_TAIL = (
    _o("ID", "identno"),
    P("Speed", "speeddata"),
    _o("V", "num"),
    _o("T", "num"),
    P("Zone", "zonedata"),
    _o("Z", "num"),
    _o("Inpos", "stoppointdata"),
    P("Tool", "tooldata"),
    _o("WObj", "wobjdata"),
    _o("Corr"),
    _o("TLoad", "loaddata"),
)
_SOCKET = P("Socket", "socketdev", var=True)
_INTERRUPT = P("Interrupt", "intnum", var=True)
_SINGLE = (_o("Single"), _o("SingleSafe"))


def _wider(base: Routine, *more: P) -> Routine:
    """Return ``base`` with more optional parameters (RAPID's, beyond the twin's subset)."""
    return Routine(base.params + more, base.returns, base.source, base.since)


_WRITE_MORE = (_o("Pos", "pos"), _o("Orient", "orient"))

WIDE_INSTRUCTIONS: dict[str, Routine] = {
    # \Pos \Orient (TPWrite, Write), \AllMoveTasks (Stop): unconfirmed; controller-loaded
    # in the COMPAS RRC modules (compas-rrc/compas_rrc_start@4b831ac)
    "tpwrite": _wider(INSTRUCTIONS["tpwrite"], *_WRITE_MORE),
    "write": _wider(INSTRUCTIONS["write"], *_WRITE_MORE),
    "stop": _wider(INSTRUCTIONS["stop"], _o("AllMoveTasks")),
    # AliasIO FromSignal (a configured signal's name, or a string naming it), ToSignal (a
    # signal variable of the module): unconfirmed; controller-loaded with a string in
    # SDEBEUL/Kraker1@5a5835c mSettings_Sations.sys
    "aliasio": _r(P("FromSignal", SIGNAL_NAME), P("ToSignal", SIGNAL_NAME, var=True)),
    "movej": _r(_o("Conc"), P("ToPoint", "robtarget"), *_MOVE_TAIL, source=_MOVEJ),
    "movel": _r(_o("Conc"), P("ToPoint", "robtarget"), *_MOVE_TAIL),
    "movec": _r(_o("Conc"), P("CirPoint", "robtarget"), P("ToPoint", "robtarget"), *_MOVE_TAIL),
    "confj": _r(_o("On"), _o("Off")),
    "confl": _r(_o("On"), _o("Off")),
    "singarea": _r(_o("Wrist"), _o("LockAxis4"), _o("Off")),
    "accset": _r(P("Acc", "num"), P("Ramp", "num"), _o("FinePointRamp", "num")),
    "velset": _r(P("Override", "num"), P("Max", "num")),
    "stopmove": _r(_o("Quick"), _o("AllMotionTasks")),
    "startmove": _r(_o("AllMotionTasks")),
    "clearpath": _r(),
    "waitrob": _r(_o("InPos"), _o("ZeroSpeed")),
    "setdo": _r(_o("SDelay", "num"), _o("Sync"), P("Signal", "signaldo"), P("Value", "dionum")),
    "set": _r(P("Signal", "signaldo")),
    "reset": _r(P("Signal", "signaldo")),
    "pulsedo": _r(_o("High"), _o("PLength", "num"), P("Signal", "signaldo")),
    "invertdo": _r(P("Signal", "signaldo")),
    "setao": _r(P("Signal", "signalao"), P("Value", "num"), source=f"{_RM}, p. 409"),
    "setgo": _r(P("Signal", "signalgo"), P("Value", "anynum")),
    "waitdi": _r(
        P("Signal", "signaldi"),
        P("Value", "dionum"),
        _o("MaxTime", "num"),
        _o("TimeFlag", "bool", True),
    ),
    "waitdo": _r(
        P("Signal", "signaldo"),
        P("Value", "dionum"),
        _o("MaxTime", "num"),
        _o("TimeFlag", "bool", True),
    ),
    "waituntil": _r(
        _o("InPos"),
        P("Cond", "bool"),
        _o("MaxTime", "num"),
        _o("TimeFlag", "bool", True),
        _o("PollRate", "num"),
        _o("Visualize"),
        _o("Header", "string"),
        _o("Message", "string"),
        _o("MsgArray", "anytype"),  # a string array
        _o("Icon", "icondata"),
        _o("Image", "string"),
        _o("VisualizeTime", "num"),
        _o("UIActiveSignal", "signaldo"),
    ),
    "waittestandset": _r(P("Object", "bool", var=True)),
    "socketcreate": _r(_SOCKET, _o("UDP")),
    "socketconnect": _r(_SOCKET, P("Address", "string"), P("Port", "num"), _o("Time", "num")),
    "socketbind": _r(_SOCKET, P("LocalAddress", "string"), P("LocalPort", "num")),
    "socketlisten": _r(_SOCKET),
    "socketaccept": _r(
        _SOCKET,
        P("ClientSocket", "socketdev", var=True),
        _o("ClientAddress", "string", True),
        _o("Time", "num"),
    ),
    "socketsend": _r(
        _SOCKET,
        _o("Str", "string"),
        _o("RawData", "rawbytes"),
        _o("Data", "anytype"),
        _o("NoOfBytes", "num"),
    ),
    "socketreceive": _r(
        _SOCKET,
        _o("Str", "string", True),
        _o("RawData", "rawbytes", True),
        _o("Data", "anytype", True),
        _o("ReadNoOfBytes", "num"),
        _o("NoRecBytes", "num", True),
        _o("Time", "num"),
    ),
    "socketclose": _r(_SOCKET),
    "isignaldi": _r(
        *_SINGLE, P("Signal", "signaldi"), P("TriggValue", "dionum"), _INTERRUPT, source=_RM
    ),
    "isignaldo": _r(*_SINGLE, P("Signal", "signaldo"), P("TriggValue", "dionum"), _INTERRUPT),
    "itimer": _r(*_SINGLE, P("Time", "num"), _INTERRUPT),
    "idelete": _r(P("Interrupt", "intnum"), source=_RM),
    "isleep": _r(P("Interrupt", "intnum")),
    "iwatch": _r(P("Interrupt", "intnum")),
    "ienable": _r(),
    "idisable": _r(),
    "errwrite": _r(
        _o("W"),
        _o("I"),
        P("Header", "string"),
        P("Reason", "string"),
        _o("RL2", "string"),
        _o("RL3", "string"),
        _o("RL4", "string"),
    ),
    "packrawbytes": _r(
        P("Value", "anytype"),
        P("RawData", "rawbytes", var=True),
        _o("Network"),
        P("StartIndex", "num"),
        _o("Hex1"),
        _o("IntX", "num"),
        _o("Float4"),
        _o("ASCII"),
    ),
    "unpackrawbytes": _r(
        P("RawData", "rawbytes"),
        _o("Network"),
        P("StartIndex", "num"),
        P("Value", "anytype", var=True),
        _o("Hex1"),
        _o("IntX", "num"),
        _o("Float4"),
        _o("ASCII", "num"),
    ),
    "copyrawbytes": _r(
        P("FromRawData", "rawbytes"),
        P("FromIndex", "num"),
        P("ToRawData", "rawbytes", var=True),
        P("ToIndex", "num"),
        _o("NoOfBytes", "num"),
    ),
    "clearrawbytes": _r(P("RawData", "rawbytes", var=True), _o("FromIndex", "num")),
    "skipwarn": _r(),
    "exitcycle": _r(),
}
"""Instructions beyond the subset, lower-case name → signature (MoveJ: its page; ISignalDI,
IDelete: RM p. 112; the rest unconfirmed)."""

WIDE_FUNCTIONS: dict[str, Routine] = {
    "strpart": _r(P("Str", "string"), P("ChPos", "num"), P("Len", "num"), returns="string"),
    "strfind": _r(
        P("Str", "string"), P("ChPos", "num"), P("Set", "string"), _o("NotInSet"), returns="num"
    ),
    "strmatch": _r(P("Str", "string"), P("ChPos", "num"), P("Pattern", "string"), returns="num"),
    "strmemb": _r(P("Str", "string"), P("ChPos", "num"), P("Set", "string"), returns="bool"),
    "strmap": _r(
        P("Str", "string"), P("FromMap", "string"), P("ToMap", "string"), returns="string"
    ),
    "strtoval": _r(P("Str", "string"), P("Val", "anytype", var=True), returns="bool"),
    "valtostr": _r(P("Val", "anytype"), returns="string"),
    "dinput": _r(P("Signal", "signaldi"), returns="dionum"),
    "doutput": _r(P("Signal", "signaldo"), returns="dionum"),
    "testdi": _r(P("Signal", "signaldi"), returns="bool"),
    "goutput": _r(P("Signal", "signalgo"), returns="num"),
    "aoutput": _r(P("Signal", "signalao"), returns="num"),
    "socketgetstatus": _r(P("Socket", "socketdev"), returns="socketstatus"),
    "rawbyteslen": _r(P("RawData", "rawbytes"), returns="num"),
    "testandset": _r(P("Object", "bool", var=True), returns="bool"),
    "getsysinfo": _r(
        *(_o(x) for x in "SerialNo SWVersion RobotType CtrlId LanIp CtrlLang SystemName".split()),
        _o("SWVersionName"),
        returns="string",
    ),
    "crobt": _r(
        _o("TaskRef", "num"),
        _o("TaskName", "string"),
        _o("Tool", "tooldata"),
        _o("WObj", "wobjdata"),
        returns="robtarget",
    ),
    "offs": _r(
        P("Point", "robtarget"),
        P("XOffset", "num"),
        P("YOffset", "num"),
        P("ZOffset", "num"),
        returns="robtarget",
    ),
    "reltool": _r(
        P("Point", "robtarget"),
        P("Dx", "num"),
        P("Dy", "num"),
        P("Dz", "num"),
        _o("Rx", "num"),
        _o("Ry", "num"),
        _o("Rz", "num"),
        returns="robtarget",
    ),
    "gettime": _r(_o("WDay"), _o("Hour"), _o("Min"), _o("Sec"), returns="num"),
    "dim": _r(P("ArrPar", "anytype"), P("DimNo", "num"), returns="num"),
    "opmode": _r(returns="symnum"),
    "runmode": _r(_o("Main"), returns="symnum"),
    "ispers": _r(P("DatObj", "anytype"), returns="bool"),
    "isvar": _r(P("DatObj", "anytype"), returns="bool"),
    "gettaskname": _r(_o("TaskNo", "num", True), _o("MecTaskNo", "num", True), returns="string"),
    "orientzyx": _r(P("ZAngle", "num"), P("YAngle", "num"), P("XAngle", "num"), returns="orient"),
    "eulerzyx": _r(_o("X"), _o("Y"), _o("Z"), P("Rotation", "orient"), returns="num"),
    "norient": _r(P("Rotation", "orient"), returns="orient"),
    "posemult": _r(P("Pose1", "pose"), P("Pose2", "pose"), returns="pose"),
    "poseinv": _r(P("Pose", "pose"), returns="pose"),
    "posevect": _r(P("Pose", "pose"), P("Pos", "pos"), returns="pos"),
}
"""Functions beyond the subset, lower-case name → signature (unconfirmed)."""
