"""Catalogue of RAPID motion instructions: what each positional argument is.

Roles: "to"/"cir" robot targets (or joint targets for MoveAbsJ-like
instructions), "search" (the INOUT result of a search), "speed", "zone",
"tool", and "other" for process data (signals, triggers, seam/weld data).
Optional arguments (\\WObj, \\V, \\Z, \\Conc, ...) are recognised by name.
Signatures from ABB's "Technical reference manual - RAPID Instructions".
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class MotionSpec:
    name: str
    roles: tuple[str, ...]
    joint_space: bool = False  # targets are jointtarget
    # Which configuration supervision governs the move: "joint" (ConfJ),
    # "linear" (ConfL, circular moves included), "absolute" (joint targets:
    # none), "external" (only external axes move: the arm does not).
    interpolation: str = "linear"

    @property
    def moves_arm(self) -> bool:
        return self.interpolation != "external"


_SPECS = [
    MotionSpec("MoveJ", ("to", "speed", "zone", "tool"), interpolation="joint"),
    MotionSpec("MoveL", ("to", "speed", "zone", "tool")),
    MotionSpec("MoveC", ("cir", "to", "speed", "zone", "tool")),
    MotionSpec("MoveAbsJ", ("to", "speed", "zone", "tool"), joint_space=True,
               interpolation="absolute"),
    MotionSpec("MoveExtJ", ("to", "speed", "zone"), joint_space=True,
               interpolation="external"),
    MotionSpec("MoveJDO", ("to", "speed", "zone", "tool", "other", "other"), interpolation="joint"),
    MotionSpec("MoveLDO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveCDO", ("cir", "to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveJAO", ("to", "speed", "zone", "tool", "other", "other"), interpolation="joint"),
    MotionSpec("MoveLAO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveCAO", ("cir", "to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveJGO", ("to", "speed", "zone", "tool", "other", "other"), interpolation="joint"),
    MotionSpec("MoveLGO", ("to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveCGO", ("cir", "to", "speed", "zone", "tool", "other", "other")),
    MotionSpec("MoveJSync", ("to", "speed", "zone", "tool", "other"), interpolation="joint"),
    MotionSpec("MoveLSync", ("to", "speed", "zone", "tool", "other")),
    MotionSpec("MoveCSync", ("cir", "to", "speed", "zone", "tool", "other")),
    MotionSpec("TriggJ", ("to", "speed", "other", "zone", "tool"), interpolation="joint"),
    MotionSpec("TriggL", ("to", "speed", "other", "zone", "tool")),
    MotionSpec("TriggC", ("cir", "to", "speed", "other", "zone", "tool")),
    MotionSpec("TriggJIOs", ("to", "speed", "zone", "tool"), interpolation="joint"),
    MotionSpec("TriggLIOs", ("to", "speed", "zone", "tool")),
    MotionSpec("SearchL", ("other", "search", "to", "speed", "tool")),
    MotionSpec("SearchC", ("other", "search", "cir", "to", "speed", "tool")),
    MotionSpec("SearchExtJ", ("other", "search", "to", "speed"), joint_space=True,
               interpolation="external"),
    MotionSpec("ArcL", ("to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcLStart", ("to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcLEnd", ("to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcC", ("cir", "to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcCStart", ("cir", "to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("ArcCEnd", ("cir", "to", "speed", "other", "other", "zone", "tool")),
    MotionSpec("SpotJ", ("to", "speed", "other", "tool"), interpolation="joint"),
    MotionSpec("SpotL", ("to", "speed", "other", "tool")),
    MotionSpec("PaintL", ("to", "speed", "zone", "tool")),
    MotionSpec("PaintC", ("cir", "to", "speed", "zone", "tool")),
    MotionSpec("DispL", ("to", "speed", "other", "zone", "tool")),
    MotionSpec("DispC", ("cir", "to", "speed", "other", "zone", "tool")),
]

MOTIONS: dict[str, MotionSpec] = {s.name.lower(): s for s in _SPECS}


def motion_spec(name: str) -> MotionSpec | None:
    return MOTIONS.get(name.lower())


# ---------------------------------------------------------------- motion state
# What other instructions do to the moves after them (compensate/flow.py).
# Program displacement (PDispOn/PDispSet) displaces every robtarget move
# until PDispOff; it does not apply to MoveAbsJ.
DISPLACEMENT_ON = frozenset({"pdispon", "pdispset"})
DISPLACEMENT_OFF = frozenset({"pdispoff"})
# An external axis offset moves a track that carries the robot: with a
# track, these displace robtarget moves too.
TRACK_OFFSET_ON = frozenset({"eoffson", "eoffsset"})
TRACK_OFFSET_OFF = frozenset({"eoffsoff"})
SUPERVISION = frozenset({"confj", "confl"})
# Calls whose routine is chosen at run time (like %...%).
UNKNOWN_TARGET_CALLS = frozenset({"callbyvar"})
# These move the arm other than to a programmed target: the robot's
# position after them is not known statically.
MOVES_OTHERWISE = frozenset(n.lower() for n in (
    "StepBwdPath", "PathRecMoveBwd", "PathRecMoveFwd", "RestoPath", "IndAMove", "IndCMove",
    "IndDMove", "IndRMove", "IndReset", "SoftAct", "SoftDeact", "StartMoveRetry",
    "SyncMoveOn", "SyncMoveOff", "SyncMoveResume", "SyncMoveSuspend", "SyncMoveUndo",
    "ContactL", "CSSDeactMoveL"))
# RAPID instructions (Technical reference manual - RAPID Instructions) that
# neither move the arm nor change configuration supervision or program
# displacement. A call to a name that is neither one of these nor a routine
# of the given modules is treated as unknown (it may do either).
BUILTIN_INSTRUCTIONS = frozenset(n.lower() for n in (
    "AccSet", "ActEventBuffer", "ActUnit", "Add", "AliasCamera", "AliasIO", "AliasIOReset",
    "BitClear", "BitSet", "BookErrNo", "Break", "CamFlush", "CamGetParameter",
    "CamGetResult", "CamLoadJob", "CamReqImage", "CamSetExposure", "CamSetParameter",
    "CamSetProgramMode", "CamSetRunMode", "CamStartLoadJob", "CamWaitLoadJob", "CancelLoad",
    "CapAPTrSetup", "CheckProgRef", "CirPathMode", "Clear", "ClearIOBuff", "ClearPath",
    "ClearRawBytes", "ClkReset", "ClkStart", "ClkStop", "Close", "CloseDir", "ConfJ", "ConfL",
    "CopyFile", "CopyRawBytes", "CorrClear", "CorrCon", "CorrDiscon", "CorrWrite",
    "DeactEventBuffer", "DeactUnit", "Decr", "DitherAct", "DitherDeact", "DropSensor",
    "DropWObj", "EGMActJoint", "EGMActMove", "EGMActPose", "EGMGetId", "EGMReset",
    "EGMSetupAI", "EGMSetupAO", "EGMSetupGI", "EGMSetupLTAPP", "EGMSetupUC", "EGMStop",
    "EOffsOff", "EOffsOn", "EOffsSet", "EraseModule", "ErrLog", "ErrRaise", "ErrWrite",
    "FricIdInit", "FricIdEvaluate", "FricIdSetFricLevels", "GetDataVal",
    "GetJointData", "GetSysData", "GetTrapData", "GripLoad", "HollowWristReset", "IDelete",
    "IDisable", "IEnable", "IError", "Incr", "InvertDO", "IOBusStart", "IOBusState",
    "IODisable", "IOEnable", "IPers", "IRMQMessage", "ISignalAI", "ISignalAO", "ISignalDI",
    "ISignalDO", "ISignalGI", "ISignalGO", "ISleep", "ITimer", "IVarValue", "IWatch", "Load",
    "LoadId", "MakeDir", "ManLoadIdProc", "MechUnitLoad", "MotionProcessModeSet",
    "MotionSup", "MToolRotCalib", "MToolTCPCalib", "Open", "OpenDir", "PackDNHeader",
    "PackRawBytes", "PathAccLim", "PathLengthReset", "PathLengthStart", "PathLengthStop",
    "PathRecStart", "PathRecStop", "PathResol", "PDispOff", "PDispOn", "PDispSet",
    "ProcerrRecovery", "PrxActivAndStoreRecord", "PrxActivRecord", "PrxDbgStoreRecord",
    "PrxDeactRecord", "PrxResetPos", "PrxResetRecords", "PrxSetPosOffset",
    "PrxSetRecordSampleTime", "PrxSetSyncalarm", "PrxStartRecord", "PrxStopRecord",
    "PrxStoreRecord", "PrxUseFileRecord", "PulseDO", "ReadAnyBin", "ReadBlock",
    "ReadCfgData", "ReadErrData", "ReadRawBytes", "ReadVarArr", "RemoveAllCyclicBool",
    "RemoveCyclicBool", "RemoveDir", "RemoveFile", "RenameFile", "Reset", "ResetAxisDistance",
    "ResetAxisMoveTime", "ResetPPMoved", "ResetRetryCount", "ResetTorqueMargin", "Rewind",
    "RMQEmptyQueue", "RMQFindSlot", "RMQGetMessage", "RMQGetMsgData", "RMQGetMsgHeader",
    "RMQReadWait", "RMQSendMessage", "RMQSendWait", "SafetyControllerSyncRequest", "Save",
    "SaveCfgData", "SCWrite", "SenDevice", "Set", "SetAllDataVal", "SetAO", "SetDataSearch",
    "SetDataVal", "SetDO", "SetGO", "SetLeadThrough", "SetSysData", "SetupCyclicBool",
    "SiConnect", "SiClose", "SiGetCyclic", "SingArea", "SiSetCyclic", "SkipWarn",
    "SocketAccept", "SocketBind", "SocketClose", "SocketConnect", "SocketCreate",
    "SocketListen", "SocketReceive", "SocketReceiveFrom", "SocketSend", "SocketSendTo",
    "SpeedLimAxis", "SpeedLimCheckPoint", "SpeedRefresh", "SpyStart", "SpyStop", "StartLoad",
    "StartMove", "STCalib", "STClose", "STIndGun", "STIndGunReset", "SToolRotCalib",
    "SToolTCPCalib", "Stop", "STOpen", "StopMove", "StopMoveReset", "StorePath", "STTune",
    "STTuneReset", "SupSyncSensorOff", "SupSyncSensorOn", "SyncToSensor",
    "SystemStopAction", "TestSignDefine", "TestSignReset", "TextTabInstall", "TPErase",
    "TPReadDnum", "TPReadFK", "TPReadNum", "TPShow", "TPWrite", "TriggCheckIO",
    "TriggDataCopy", "TriggDataReset", "TriggEquip", "TriggInt", "TriggIO", "TriggRampAO",
    "TriggSpeed", "TriggStopProc", "TryInt", "TuneReset", "TuneServo", "UIMsgBox", "UIShow",
    "UnLoad", "UnpackRawBytes", "VelSet", "WaitAI", "WaitAO", "WaitDI", "WaitDO", "WaitGI",
    "WaitGO", "WaitLoad", "WaitRob", "WaitSensor", "WaitSyncTask", "WaitTestAndSet",
    "WaitTime", "WaitUntil", "WaitWObj", "WarmStart", "WorldAccLim", "Write", "WriteAnyBin",
    "WriteBin", "WriteBlock", "WriteCfgData", "WriteRawBytes", "WriteStrBin", "WriteVar",
    "WZBoxDef", "WZCylDef", "WZDisable", "WZDOSet", "WZEnable", "WZFree", "WZHomeJointDef",
    "WZLimJointDef", "WZLimSup", "WZSphDef"))
# RAPID functions (Technical reference manual - RAPID Functions). They
# neither move the arm nor switch supervision or displacement; those that
# write an argument are in writes.WRITING_BUILTINS. A function call to a
# name that is neither one of these nor a function of the given modules is
# treated as an unknown call.
BUILTIN_FUNCTIONS = frozenset(n.lower() for n in (
    "Abs", "AbsDnum", "ACos", "ACosDnum", "AInput", "AND", "AOutput", "ArgName", "ASin",
    "ASinDnum", "ATan", "ATan2", "ATan2Dnum", "ATanDnum", "BitAnd", "BitAndDnum", "BitCheck",
    "BitCheckDnum", "BitLSh", "BitLShDnum", "BitNeg", "BitNegDnum", "BitOr", "BitOrDnum",
    "BitRSh", "BitRShDnum", "BitXOr", "BitXOrDnum", "ByteToStr", "CalcJointT", "CalcRobT",
    "CalcRotAxFrameZ", "CalcRotAxisFrame", "CamGetExposure", "CamGetLoadedJob", "CamGetName",
    "CamNumberOfResults", "CDate", "CJointT", "ClkRead", "CorrRead", "Cos", "CosDnum",
    "CPos", "CRobT", "CSpeedOverride", "CTime", "CTool", "CWObj", "DecToHex", "DefAccFrame",
    "DefDFrame", "DefFrame", "Dim", "DInput", "Distance", "DnumToNum", "DnumToStr",
    "DotProd", "DOutput", "EGMGetState", "EulerZYX", "EventType", "ExecHandler",
    "ExecLevel", "Exp", "FileSize", "FileTime", "FSSize", "GetAxisDistance",
    "GetAxisMoveTime", "GetMaxNumberOfCyclicBool", "GetMecUnitName", "GetModalPayLoadMode",
    "GetMotorTorque", "GetNextCyclicBool", "GetNextMechUnit", "GetNextSym",
    "GetNumberOfCyclicBool", "GetServiceInfo", "GetSignalOrigin", "GetSysInfo",
    "GetTaskName", "GetTime", "GetTSPStatus", "GetUASUserName", "GInput", "GInputDnum",
    "GOutput", "GOutputDnum", "HexToDec", "IndInpos", "IndSpeed", "IOUnitState", "IsBrakeCheckActive",
    "IsCyclicBool", "IsFile", "IsLeadThrough", "IsMechUnitActive", "IsPers", "IsStopMoveAct",
    "IsStopStateEvent", "IsSyncMoveOn", "IsSysId", "IsVar", "MaxExtLinearSpeed",
    "MaxExtReorientSpeed", "MaxRobReorientSpeed", "MaxRobSpeed", "MirPos", "ModExist",
    "ModTime", "MotionPlannerNo", "NonMotionMode", "NOrient", "NumToDnum", "NumToStr",
    "Offs", "OpMode", "OrientZYX", "ORobT", "ParIdPosValid", "ParIdRobValid",
    "PathLevel", "PathRecValidBwd", "PathRecValidFwd", "PFRestart", "PoseInv", "PoseMult",
    "PoseVect", "Pow", "PowDnum", "PPMovedInManMode", "Present", "ProgMemFree",
    "PrxGetMaxRecordpos", "RawBytesLen", "ReadBin", "ReadDir", "ReadMotor", "ReadNum",
    "ReadStr", "ReadStrBin", "ReadVar", "RelTool", "RemainingRetries", "RMQGetSlotName",
    "RobName", "RobOS", "Round", "RoundDnum", "RunMode", "SafetyControllerGetChecksum",
    "SafetyControllerGetSWVersion", "SafetyControllerGetUserChecksum", "Sin", "SinDnum",
    "SocketGetStatus", "SocketPeek", "Sqrt", "SqrtDnum", "STCalcForce", "STCalcTorque",
    "STIsCalib", "STIsClosed", "STIsIndGun", "STIsOpen", "StrDigCalc", "StrDigCmp",
    "StrFind", "StrLen", "StrMap", "StrMatch", "StrMemb", "StrOrder", "StrPart",
    "StrToByte", "StrToVal", "Tan", "TanDnum", "TaskRunMec", "TaskRunRob", "TasksInSync",
    "TestAndSet", "TestDI", "TestSignRead", "TextGet", "TextTabFreeToUse", "TextTabGet",
    "TriggDataValid", "Trunc", "TruncDnum", "Type", "UIAlphaEntry", "UIClientExist",
    "UIDnumEntry", "UIDnumTune", "UIListView", "UIMessageBox", "UINumEntry", "UINumTune",
    "ValidIO", "ValToStr", "VectMagn"))
