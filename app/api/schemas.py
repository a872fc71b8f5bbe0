"""Request and response models of the API, grouped by resource (``*In`` what a client sends,
``*Out`` what it gets back). Angles are degrees here, at the edge; radians inside."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from app.console import (
    VISIBILITY_MAX_M,
    VISIBILITY_MIN_M,
    Alarm,
    MissionStatus,
    ReplayStatus,
    Snapshot,
    VesselAdvice,
)
from app.console.commands import (
    CURRENT_MAX_MPS,
    DIRECTION_RANGE_DEG,
    HEADING_RANGE_DEG,
    REPLAY_T_MAX_S,
    SPEED_MAX,
    SPEED_MIN,
    STEPS_MAX,
    TARGET_RANGE_M,
    VESSEL_RANGE_M,
    VESSEL_SPEED_MAX_MPS,
)
from control.config import Allocation, Mode
from sim.gnc import ssa
from sim.params import GAIN_LIMITS


class _In(BaseModel):
    """What a client sends: unknown fields refused, and no coercion (true is not 1.0, "yes"
    is not true, "5" is not 5)."""

    model_config = ConfigDict(extra="forbid", strict=True)


Finite = Annotated[float, Field(allow_inf_nan=False)]


class ErrorOut(BaseModel):
    """Every error answer: what is wrong, in words that name the field and its range."""

    detail: str
    errors: list[dict[str, Any]] | None = Field(
        default=None, description="422 only: each bad field (loc, msg, type)"
    )


# ------------------------------------------------------------------ health, state
class HealthOut(BaseModel):
    status: Literal["ok", "stopped", "stalled", "broken"] = Field(
        description="ok: the loop ticks; stopped: its task ended; stalled: no tick for 2 s; "
        "broken: it ticks but its state cannot be served (state_error says why)"
    )
    t_s: float = Field(description="simulation time [s]")
    loop_running: bool
    ticks: int = Field(description="ticks of the loop so far")
    run_error: str | None = Field(
        default=None, description="why the run is stopped (divergence, a failed step), if it is"
    )
    faults: int = Field(default=0, description="errors the loop caught and survived")
    state_error: str | None = Field(
        default=None, description="why /api/state and telemetry cannot send the state, if so"
    )


class EtaOut(BaseModel):
    """A pose in NED: position [m], Euler angles [deg] (heading wrapped to [-180, 180))."""

    north_m: float
    east_m: float
    down_m: float
    roll_deg: float
    pitch_deg: float
    heading_deg: float

    @staticmethod
    def of(eta: tuple[float, ...]) -> EtaOut:
        deg = [math.degrees(ssa(a)) for a in eta[3:6]]
        return EtaOut(
            north_m=eta[0],
            east_m=eta[1],
            down_m=eta[2],
            roll_deg=deg[0],
            pitch_deg=deg[1],
            heading_deg=deg[2],
        )


class PoseOut(BaseModel):
    """[north, east, heading] of the tree (the controlled degrees of freedom)."""

    north_m: float
    east_m: float
    heading_deg: float = Field(description="unwrapped: counts whole turns")

    @staticmethod
    def of(p: tuple[float, float, float]) -> PoseOut:
        return PoseOut(north_m=p[0], east_m=p[1], heading_deg=math.degrees(p[2]))


class VesselAdviceOut(BaseModel):
    """A dock leg's advice to move the vessel (``vessel = "advise"``), which the leg waits for
    the operator to follow (POST /api/environment/vessel/apply-advice follows it)."""

    text: str = Field(description="the leg's words: 'move the vessel 4.8 m towards 016 deg ...'")
    crane_tip_ne_m: tuple[float, float] = Field(description="where the crane tip should go")
    t_s: float = Field(description="run time when it was given [s]")
    distance_m: float = Field(description="how far the vessel should move, from where it stood")
    bearing_deg: float = Field(description="which way, as a compass bearing")
    applied: bool = Field(description="the vessel is commanded to the advised place")
    to_go_m: float = Field(description="the crane tip's distance from the advised place now")

    @staticmethod
    def of(a: VesselAdvice) -> VesselAdviceOut:
        return VesselAdviceOut(**a.__dict__)


class MissionStatusOut(BaseModel):
    name: str | None
    state: str = Field(
        description="idle | running | completed | failed | aborted | diverged | replay"
    )
    leg_index: int | None = Field(description="1-based index of the running leg")
    legs_total: int
    leg_type: str | None
    leg_name: str | None
    result: dict[str, Any] | None
    vessel_advice: VesselAdviceOut | None = Field(
        default=None,
        description="the running dock leg's newest advice to move the vessel, until the leg "
        "or the mission ends",
    )

    @staticmethod
    def of(m: MissionStatus) -> MissionStatusOut:
        advice = m.vessel_advice
        return MissionStatusOut(
            **{**m.__dict__, "vessel_advice": VesselAdviceOut.of(advice) if advice else None}
        )


class AlarmOut(BaseModel):
    name: str
    active: bool
    message: str

    @staticmethod
    def of(a: Alarm) -> AlarmOut:
        return AlarmOut(name=a.name, active=a.active, message=a.message)


class ThrusterOut(BaseModel):
    index: int
    utilisation: float
    force_newton: float
    saturated: bool


class CurrentOut(BaseModel):
    speed_mps: float
    direction_deg: float = Field(description="direction the water flows towards")


class ReplayOut(BaseModel):
    name: str
    t_s: float
    start_s: float
    end_s: float
    playing: bool
    complete: bool
    marks: list[tuple[float, str]] = Field(
        default_factory=list, description="events on the scrub bar: [t_s, label]"
    )
    jumps: list[tuple[float, str]] = Field(
        default_factory=list, description="the marked events in words: [t_s, text]"
    )

    @staticmethod
    def of(r: ReplayStatus) -> ReplayOut:
        return ReplayOut(**r.__dict__)


class LoopOut(BaseModel):
    paused: bool
    speed: float
    period_s: float
    jitter_median_ms: float
    jitter_p99_ms: float
    ticks: int
    overruns: int
    step_ms_p99: float


class StateOut(BaseModel):
    """Everything the console shows, as of one tick of the loop."""

    seq: int
    source: Literal["live", "replay"]
    t_s: float
    tree_eta_n: EtaOut
    rov_eta_n: EtaOut
    reference: PoseOut
    estimate: PoseOut
    mode: str
    allocation: str | None
    grip: bool | None
    mission: MissionStatusOut
    thrusters: list[ThrusterOut]
    alarms: list[AlarmOut]
    crane_tip_n: list[float]
    wire_length_m: float
    wire_tension_newton: float | None
    current: CurrentOut
    recording: str | None
    replay: ReplayOut | None
    loop: LoopOut
    warnings: list[str]
    error: str | None

    @staticmethod
    def of(s: Snapshot) -> StateOut:
        from app.console import SATURATED

        return StateOut(
            seq=s.seq,
            source=s.source,
            t_s=s.t_s,
            tree_eta_n=EtaOut.of(s.tree_eta_n),
            rov_eta_n=EtaOut.of(s.rov_eta_n),
            reference=PoseOut.of(s.eta_ref),
            estimate=PoseOut.of(s.eta_hat),
            mode=s.mode,
            allocation=s.allocation,
            grip=s.grip,
            mission=MissionStatusOut.of(s.mission),
            thrusters=[
                ThrusterOut(index=i + 1, utilisation=u, force_newton=f, saturated=u >= SATURATED)
                for i, (u, f) in enumerate(
                    zip(s.thruster_utilisation, s.thruster_force_newton, strict=True)
                )
            ],
            alarms=[AlarmOut.of(a) for a in s.alarms],
            crane_tip_n=list(s.crane_tip_n),
            wire_length_m=s.wire_length_m,
            wire_tension_newton=s.wire_tension_newton,
            current=CurrentOut(
                speed_mps=s.current_speed_mps, direction_deg=math.degrees(s.current_direction_rad)
            ),
            recording=s.recording,
            replay=ReplayOut.of(s.replay) if s.replay else None,
            loop=LoopOut(
                paused=s.paused,
                speed=s.speed,
                **{
                    k: getattr(s.stats, k)
                    for k in (
                        "period_s",
                        "jitter_median_ms",
                        "jitter_p99_ms",
                        "ticks",
                        "overruns",
                        "step_ms_p99",
                    )
                },
            ),
            warnings=list(s.warnings),
            error=s.error,
        )


# ------------------------------------------------------------------ run
class SpeedIn(_In):
    speed: float = Field(
        ge=SPEED_MIN, le=SPEED_MAX, allow_inf_nan=False, description="simulated s per wall s"
    )


class StepIn(_In):
    steps: int = Field(default=1, ge=1, le=STEPS_MAX, description="plant steps of 0.01 s")


class ResetIn(_In):
    params: str | None = Field(
        default=None, max_length=100, description="parameter set (default: the running one)"
    )
    depth_m: float | None = Field(default=None, gt=5.0, le=4000.0, allow_inf_nan=False)


class CommandOut(BaseModel):
    ok: bool = True
    result: dict[str, Any] = {}


# ------------------------------------------------------------------ gains
def _gain_list(limit: float) -> Any:
    return Annotated[
        list[Annotated[float, Field(ge=0.0, le=limit, allow_inf_nan=False)]],
        Field(
            min_length=3,
            max_length=3,
            description="[surge, sway, yaw], each in [0, 4 x the running parameter set's "
            "gain] (the ranges per axis are in prefixItems)",
        ),
    ]


class GainsIn(_In):
    """Tree-controller gains [surge, sway, yaw] (appendix B)."""

    kp: _gain_list(GAIN_LIMITS["kp"])  # type: ignore[valid-type]
    ki: _gain_list(GAIN_LIMITS["ki"])  # type: ignore[valid-type]
    kd: _gain_list(GAIN_LIMITS["kd"])  # type: ignore[valid-type]


class GainsOut(BaseModel):
    kp: list[float]
    ki: list[float]
    kd: list[float]
    source: Literal["live", "replay"] = "live"


# ------------------------------------------------------------------ control
class ControlOut(BaseModel):
    mode: str
    allocation: str | None
    grip: bool | None
    reference: PoseOut


class ModeIn(_In):
    mode: Mode


class AllocationIn(_In):
    allocation: Allocation


class GripIn(_In):
    grip: bool


class TargetIn(_In):
    north_m: float = Field(ge=-TARGET_RANGE_M, le=TARGET_RANGE_M, allow_inf_nan=False)
    east_m: float = Field(ge=-TARGET_RANGE_M, le=TARGET_RANGE_M, allow_inf_nan=False)
    heading_deg: float = Field(
        ge=-HEADING_RANGE_DEG,
        le=HEADING_RANGE_DEG,
        allow_inf_nan=False,
        description="reached the short way round",
    )


# ------------------------------------------------------------------ environment
class EnvironmentOut(BaseModel):
    current: CurrentOut
    crane_tip_n: list[float]
    wire_length_m: float
    wire_tension_newton: float | None


class CurrentIn(_In):
    speed_mps: float = Field(ge=0.0, le=CURRENT_MAX_MPS, allow_inf_nan=False)
    direction_deg: float = Field(
        ge=-DIRECTION_RANGE_DEG,
        le=DIRECTION_RANGE_DEG,
        allow_inf_nan=False,
        description="direction the water flows towards",
    )


class VisibilityIn(_In):
    visibility_m: float = Field(
        ge=VISIBILITY_MIN_M,
        le=VISIBILITY_MAX_M,
        allow_inf_nan=False,
        description="how far the water lets one see (turbid 2 m to clear 30 m)",
    )


class VisibilityOut(BaseModel):
    visibility_m: float


class VesselIn(_In):
    north_m: float = Field(
        ge=-VESSEL_RANGE_M, le=VESSEL_RANGE_M, allow_inf_nan=False, description="crane tip north"
    )
    east_m: float = Field(ge=-VESSEL_RANGE_M, le=VESSEL_RANGE_M, allow_inf_nan=False)
    speed_mps: float = Field(
        default=0.5,
        gt=0.0,
        le=VESSEL_SPEED_MAX_MPS,
        allow_inf_nan=False,
        description="vessel speed on the way [m/s]",
    )


# ------------------------------------------------------------------ missions
class MissionSummaryOut(BaseModel):
    name: str
    description: str
    legs: int
    params: str
    source: Literal["library", "upload"]


class MissionListOut(BaseModel):
    library: list[MissionSummaryOut]
    uploaded: list[MissionSummaryOut]
    leg_types: list[str]


class MissionOut(BaseModel):
    name: str
    mission: dict[str, Any]
    toml: str


class MissionTextIn(_In):
    """A mission as TOML text or as a JSON object (exactly one)."""

    toml: str | None = Field(default=None, max_length=200_000)
    mission: dict[str, Any] | None = None


class ValidationOut(BaseModel):
    valid: bool
    errors: list[str]
    name: str | None = None
    legs: int | None = None


class UploadOut(BaseModel):
    name: str


class StartMissionIn(_In):
    name: str = Field(min_length=1, max_length=200, description="library or uploaded mission")
    run_legs: bool = Field(default=True, description="false: load the set-up only")


# ------------------------------------------------------------------ recordings, replay
class RecordingStartIn(_In):
    label: str = Field(default="", pattern=r"^[A-Za-z0-9._-]{0,60}$")


class RecordingOut(BaseModel):
    name: str


class RecordingInfoOut(BaseModel):
    name: str
    size_bytes: int
    modified: str


class RecordingListOut(BaseModel):
    recordings: list[RecordingInfoOut]
    recording: str | None


class ReplayOpenIn(_In):
    name: str = Field(min_length=1, max_length=200)


class ReplaySeekIn(_In):
    t_s: float = Field(ge=0.0, le=REPLAY_T_MAX_S, allow_inf_nan=False)


class ReplayStateOut(BaseModel):
    replay: ReplayOut | None
