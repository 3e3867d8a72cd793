//! The grasp sequence as a hierarchical state machine (statig).
//!
//! ```text
//! idle ─Start─▶ ┌ grasping ─────────────────────────────────────────────┐
//!               │ prepare ─▶ detect ─▶ approach ─▶ trial_grasp ─▶ evaluate │──▶ done
//!               │    └─── touch only ───▶▲              └─▶ search ◀─▶┘  │
//!               │                                   regrasp ◀─┘  ▲  │    │──▶ failed
//!               │                                      └─▶ verify ┘──┘    │
//!               └───── DeviceFault, Abort ──────────────────────────▶ fault
//! ```
//!
//! The machine does no I/O. A state's entry action leaves a `Command` in
//! the context; the runner has the cell carry it out and feeds back the
//! answering `Event`. The `grasping` superstate owns what every step
//! shares: a device fault or an abort leads to `fault`, whose command makes
//! the cell safe. Every transition is logged once, by `after_transition`,
//! into the run record.
//!
//! When the camera cannot place the cable (no cable detected, the detector
//! unusable, or a touch-only task) and the task has a prior, the run
//! searches by touch: the trial grasp goes to the prior's mean, and while
//! no grasp has felt the cable, `search` moves to the next pose of
//! `perception::tactile::search` and grasps again. The first grasp that
//! feels the cable is the trial grasp, judged as any other.

use nalgebra::{Isometry3, Translation3};
use statig::prelude::*;

use super::command::{Command, Event};
use super::plan::Plan;
use crate::detector::Detections;
use crate::geometry::{LineInSensor, planar_to_spatial, t_corr_with_gain};
use crate::hw::gripper::GripOutcome;
use crate::hw::tactile::TactileFrame;
use crate::hw::{DeviceError, DeviceKind};
use crate::perception::tactile::search::{Prior, SearchPose, covered_half_width_mm, search_poses};
use crate::perception::tactile::{Bias, BiasEstimator, FitError, RawFrame};
use crate::record::{
    DetectedCable, Failure, GraspRecord, RunOutcome, RunRecord, Skip, Skipped, TouchOnlyRecord,
    TransitionRecord, Truth, WhyTouchOnly,
};

/// What the machine shares with the runner: lent to the machine for each
/// event, owned by the runner in between, so that the runner can change
/// the plan between two events (the REPL's `set`).
#[derive(Debug)]
pub struct Context {
    /// The cell's clock when the event being handled arrived.
    pub now_s: f64,
    /// What the cell must do next, left by the latest entry action.
    pub command: Option<Command>,
    /// What the task asks for; read by every entry action and judgement,
    /// so a change applies from the next command on.
    pub plan: Plan,
    pub record: RunRecord,
}

impl Context {
    pub fn new(plan: Plan, record: RunRecord) -> Self {
        Self {
            now_s: 0.0,
            command: None,
            plan,
            record,
        }
    }
}

/// The machine's own storage: what it learnt on the way.
pub struct GraspTask {
    /// Per-taxel rest voltages, measured in `prepare`.
    bias: Option<Bias>,
    /// Where the next grasp puts the TCP.
    base_from_tcp_aim: Isometry3<f64>,
    /// The arm's measured pose at the latest grasp.
    base_from_tcp_grasped: Isometry3<f64>,
    regrasps_done: u32,
    /// The search by touch under way, from its start until a grasp feels
    /// the cable.
    searching: Option<Search>,
}

impl GraspTask {
    pub fn new() -> Self {
        Self {
            bias: None,
            base_from_tcp_aim: Isometry3::identity(),
            base_from_tcp_grasped: Isometry3::identity(),
            regrasps_done: 0,
            searching: None,
        }
    }
}

/// A search by touch: where it started, the poses it tries in order, and
/// how many it has aimed at.
struct Search {
    prior: Prior,
    poses: Vec<SearchPose>,
    made: u32,
}

impl Default for GraspTask {
    fn default() -> Self {
        Self::new()
    }
}

#[state_machine(
    initial = "State::idle()",
    state(derive(Debug, Clone, Copy, PartialEq, Eq)),
    superstate(derive(Debug, Clone, Copy, PartialEq, Eq)),
    after_transition = "Self::after_transition"
)]
impl GraspTask {
    /// Start → prepare.
    #[state]
    fn idle(event: &Event) -> Outcome<State> {
        match event {
            Event::Start => Transition(State::prepare()),
            _ => Handled,
        }
    }

    /// Tactile (bias frames) → detect; too few frames → fault.
    #[state(superstate = "grasping", entry_action = "enter_prepare")]
    fn prepare(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        match event {
            Event::Tactile { frames, .. } => {
                let mut estimator = BiasEstimator::new(context.plan.bias_frames);
                match frames.iter().find_map(|frame| estimator.push(&frame.raw)) {
                    Some(bias) => {
                        self.bias = Some(bias);
                        match context.plan.prior.filter(|_| context.plan.touch_only) {
                            Some(prior) => self.start_search(context, prior, WhyTouchOnly::Forced),
                            None => Transition(State::detect()),
                        }
                    }
                    None => {
                        let needed = context.plan.bias_frames;
                        let error = format!("{} bias frames read, {needed} needed", frames.len());
                        fault(context, None, error)
                    }
                }
            }
            _ => Super,
        }
    }

    /// Detected (a cable) → approach; Detected (none) → approach the
    /// prior's mean, searching, or failed without a prior; an unusable
    /// detector → the same with a prior, else fault.
    #[state(superstate = "grasping", entry_action = "enter_detect")]
    fn detect(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        match event {
            Event::Detected(detections) => {
                let skipped = detections.skipped.iter().map(Skip::from);
                context.record.skipped.extend(skipped);
                self.on_detected(context, detections)
            }
            Event::DeviceFault(error) if vision_unusable(error) => match context.plan.prior {
                Some(prior) => {
                    let error = error.to_string();
                    self.start_search(context, prior, WhyTouchOnly::DetectorUnusable { error })
                }
                None => Super,
            },
            _ => Super,
        }
    }

    /// Arrived (at the standoff) → trial_grasp.
    #[state(superstate = "grasping", entry_action = "enter_approach")]
    fn approach(event: &Event) -> Outcome<State> {
        match event {
            Event::Arrived => Transition(State::trial_grasp()),
            _ => Super,
        }
    }

    /// Grasped (holding) → evaluate; Grasped (empty) → search (poses
    /// left), or failed.
    #[state(superstate = "grasping", entry_action = "enter_trial_grasp")]
    fn trial_grasp(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        self.on_grasped(context, event, State::evaluate())
    }

    /// Grasped (holding) → evaluate; Grasped (empty) → search again (poses
    /// left), or failed.
    #[state(superstate = "grasping", entry_action = "enter_search")]
    fn search(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        self.on_grasped(context, event, State::evaluate())
    }

    /// Tactile → done (within tolerance), regrasp, search (nothing felt,
    /// poses left), or failed.
    #[state(superstate = "grasping", entry_action = "enter_read_tactile")]
    fn evaluate(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        match event {
            Event::Tactile { frames, true_line } => self.judge(context, frames, *true_line),
            _ => Super,
        }
    }

    /// Grasped (holding) → verify; Grasped (empty) → failed.
    #[state(superstate = "grasping", entry_action = "enter_regrasp")]
    fn regrasp(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        self.on_grasped(context, event, State::verify())
    }

    /// Tactile → done (within tolerance), regrasp, or failed.
    #[state(superstate = "grasping", entry_action = "enter_read_tactile")]
    fn verify(&mut self, context: &mut Context, event: &Event) -> Outcome<State> {
        match event {
            Event::Tactile { frames, true_line } => self.judge(context, frames, *true_line),
            _ => Super,
        }
    }

    /// DeviceFault, Abort → fault, for every step of the sequence.
    #[superstate]
    fn grasping(context: &mut Context, event: &Event) -> Outcome<State> {
        match event {
            Event::DeviceFault(error) => fault(context, Some(error.device()), error.to_string()),
            Event::Abort => fault(context, None, "aborted by the operator".into()),
            _ => Handled,
        }
    }

    /// The cable is held at the target pose.
    #[state]
    fn done(event: &Event) -> Outcome<State> {
        let _ = event;
        Handled
    }

    /// The task did not reach its goal; the cell is fine.
    #[state]
    fn failed(event: &Event) -> Outcome<State> {
        let _ = event;
        Handled
    }

    /// Stopped → stays: the cell is safe, the run is over.
    #[state(entry_action = "enter_fault")]
    fn fault(context: &mut Context, event: &Event) -> Outcome<State> {
        if let Event::Stopped { problems } = event {
            context.record.safe_stop_problems = problems.iter().map(ToString::to_string).collect();
        }
        Handled
    }

    #[action]
    fn enter_prepare(&mut self, context: &mut Context) {
        context.command = Some(Command::Prepare {
            open_mm: context.plan.open_mm,
            bias_frames: context.plan.bias_frames,
        });
    }

    #[action]
    fn enter_detect(context: &mut Context) {
        context.command = Some(Command::Detect);
    }

    #[action]
    fn enter_approach(&mut self, context: &mut Context) {
        context.command = Some(Command::MoveTo {
            base_from_tcp: standoff_from(&self.base_from_tcp_aim, context.plan.standoff_mm),
            speed_mm_s: context.plan.speed_mm_s,
        });
    }

    #[action]
    fn enter_trial_grasp(&mut self, context: &mut Context) {
        context.command = Some(Command::Grasp {
            base_from_tcp: self.base_from_tcp_aim,
            speed_mm_s: context.plan.speed_mm_s,
            grip_current_a: context.plan.grip_current_a,
        });
    }

    #[action]
    fn enter_search(&mut self, context: &mut Context) {
        if self.aim_search(context) {
            context.command = Some(Command::Probe {
                base_from_tcp: self.base_from_tcp_aim,
                speed_mm_s: context.plan.speed_mm_s,
                open_mm: context.plan.open_mm,
                retreat_mm: context.plan.retreat_mm,
                grip_current_a: context.plan.grip_current_a,
            });
        }
    }

    #[action]
    fn enter_read_tactile(&mut self, context: &mut Context) {
        context.command = Some(Command::ReadTactile {
            frames: context.plan.average_frames,
        });
    }

    #[action]
    fn enter_regrasp(&mut self, context: &mut Context) {
        self.regrasps_done += 1;
        context.command = Some(Command::Regrasp {
            base_from_tcp: self.base_from_tcp_aim,
            speed_mm_s: context.plan.speed_mm_s,
            open_mm: context.plan.open_mm,
            retreat_mm: context.plan.retreat_mm,
            grip_current_a: context.plan.grip_current_a,
        });
    }

    #[action]
    fn enter_fault(&mut self, context: &mut Context) {
        context.command = Some(Command::SafeStop {
            open_mm: context.plan.open_mm,
        });
    }
}

/// Whether `error` says that the camera cannot place the cable, and
/// nothing worse: the detector or camera cannot work as set up, the
/// pipeline failed on the image, or the image could not be read.
fn vision_unusable(error: &DeviceError) -> bool {
    matches!(
        error,
        DeviceError::Unusable {
            device: DeviceKind::Detector | DeviceKind::Camera,
            ..
        } | DeviceError::Vision { .. }
            | DeviceError::Image { .. }
    )
}

/// The TCP's pose that puts the cable of grasp frame `base_from_cable` at
/// the plan's target pose on the pad.
fn aim_at(plan: &Plan, base_from_cable: &Isometry3<f64>) -> Isometry3<f64> {
    let sensor_from_cable = planar_to_spatial(&plan.target.sensor_from_line());
    base_from_cable * sensor_from_cable.inverse() * plan.tcp_from_sensor.inverse()
}

impl Search {
    /// After a grasp that felt nothing: the next pose, or failed when none
    /// is left.
    fn next(&self, context: &mut Context) -> Outcome<State> {
        if (self.made as usize) < self.poses.len() {
            return Transition(State::search());
        }
        let prior = &self.prior;
        fail(
            context,
            Failure::SearchExhausted {
                search_moves: self.made,
                prior_in_base_mm: prior.base_from_cable.translation.vector.into(),
                position_sigma_mm: prior.position_sigma_mm,
                angle_sigma_rad: prior.angle_sigma_rad,
                covered_across_mm: covered_half_width_mm(&self.poses, context.plan.fit.pitch_mm),
            },
        )
    }
}

/// The pose `standoff_mm` back from `base_from_tcp` along the approach
/// axis (the TCP's z).
fn standoff_from(base_from_tcp: &Isometry3<f64>, standoff_mm: f64) -> Isometry3<f64> {
    base_from_tcp * Translation3::new(0.0, 0.0, -standoff_mm)
}

impl GraspTask {
    /// Approach the first cable detected (noting the search by touch it
    /// spares, when the task has a prior); else search from the prior, or
    /// fail without one.
    fn on_detected(&mut self, context: &mut Context, detections: &Detections) -> Outcome<State> {
        context.record.detected = detections
            .cables
            .iter()
            .map(|cable| DetectedCable {
                confidence: cable.confidence,
                base_from_cable: cable.base_from_cable,
            })
            .collect();
        match (detections.cables.first(), context.plan.prior) {
            (Some(detection), prior) => {
                if prior.is_some() {
                    context.record.skipped.push(Skip {
                        what: Skipped::TouchSearch,
                        why: "the camera placed the cable".to_owned(),
                    });
                }
                self.base_from_tcp_aim = aim_at(&context.plan, &detection.base_from_cable);
                Transition(State::approach())
            }
            (None, Some(prior)) => self.start_search(context, prior, WhyTouchOnly::NoCableDetected),
            (None, None) => fail(context, Failure::NothingDetected),
        }
    }

    /// Starts a search by touch from `prior`: the trial grasp goes to its
    /// first pose, the prior's mean.
    fn start_search(
        &mut self,
        context: &mut Context,
        prior: Prior,
        why: WhyTouchOnly,
    ) -> Outcome<State> {
        context.record.touch_only = Some(TouchOnlyRecord {
            why,
            search_moves: 0,
            misses: Vec::new(),
        });
        let poses = search_poses(&prior, context.plan.fit.pitch_mm);
        self.searching = Some(Search {
            prior,
            poses,
            made: 0,
        });
        // A search has at least one pose, the prior's mean.
        self.aim_search(context);
        Transition(State::approach())
    }

    /// Aims at the search's next pose and counts the move; `false` if no
    /// search is under way or it has no pose left.
    fn aim_search(&mut self, context: &mut Context) -> bool {
        let Some(search) = &mut self.searching else {
            return false;
        };
        let Some(pose) = search.poses.get(search.made as usize) else {
            return false;
        };
        self.base_from_tcp_aim = aim_at(&context.plan, &pose.base_from_cable(&search.prior));
        search.made += 1;
        if let Some(touch_only) = &mut context.record.touch_only {
            touch_only.search_moves = search.made;
        }
        true
    }

    /// Grasped (holding) → `next`; Grasped (empty) → the search's next
    /// pose, or failed; any other event → the superstate.
    fn on_grasped(&mut self, context: &mut Context, event: &Event, next: State) -> Outcome<State> {
        let Event::Grasped {
            base_from_tcp,
            grip,
        } = event
        else {
            return Super;
        };
        match grip {
            GripOutcome::Holding { .. } => {
                self.base_from_tcp_grasped = *base_from_tcp;
                Transition(next)
            }
            GripOutcome::Empty => match &self.searching {
                Some(search) => search.next(context),
                None => fail(
                    context,
                    Failure::GraspedNothing {
                        attempt: self.regrasps_done,
                    },
                ),
            },
        }
    }

    /// Estimates the cable's pose from the frames, records the grasp, and
    /// decides: done, regrasp (aiming with T_corr) or failed.
    fn judge(
        &mut self,
        context: &mut Context,
        frames: &[TactileFrame],
        true_line: Option<LineInSensor>,
    ) -> Outcome<State> {
        let attempt = self.regrasps_done;
        let raw: Vec<RawFrame> = frames.iter().map(|frame| frame.raw).collect();
        let Some(map) = self.bias.as_ref().and_then(|bias| bias.remove_mean(&raw)) else {
            return fault(context, None, "no tactile frames to evaluate".into());
        };
        let plan = &context.plan;
        let fit = plan.estimator.estimate(&map, &plan.fit, true_line);
        let estimated_error = fit
            .as_ref()
            .ok()
            .map(|fit| fit.line().error_to(&context.plan.target));
        let grasp = GraspRecord {
            attempt,
            t_s: context.now_s,
            base_from_tcp: self.base_from_tcp_grasped,
            map,
            fit: fit.as_ref().ok().cloned(),
            estimated_error,
            truth: true_line.map(|line| Truth {
                line,
                error: line.error_to(&context.plan.target),
                estimate_error: fit.as_ref().ok().map(|fit| fit.line().error_to(&line)),
            }),
            shapes: None,
        };
        if let (Some(search), Err(FitError::NoContact { .. })) = (&self.searching, &fit) {
            if let Some(touch_only) = &mut context.record.touch_only {
                touch_only.misses.push(grasp);
            }
            return search.next(context);
        }
        // Whatever the pad feels ends a search: this is its trial grasp.
        self.searching = None;
        context.record.grasps.push(grasp);
        let fit = match fit {
            Ok(fit) => fit,
            Err(FitError::NoContact { peak_dv_v, .. }) => {
                return fail(context, Failure::NoContact { attempt, peak_dv_v });
            }
            Err(error) => {
                let error = error.to_string();
                return fail(context, Failure::FitFailed { attempt, error });
            }
        };
        let line = fit.line();
        let error = line.error_to(&context.plan.target);
        if error.within(&context.plan.tolerance) {
            let (max, tolerance) = (context.plan.max_regrasps, context.plan.tolerance);
            if attempt < max {
                context.record.skipped.push(Skip {
                    what: Skipped::Regrasp,
                    why: format!(
                        "grasp {attempt} within tolerance (|n| {:.3} ≤ {} mm, |α| {:.4} ≤ {} rad): {} of {max} regrasp(s) unused",
                        error.n_mm.abs(),
                        tolerance.n_mm,
                        error.alpha_rad.abs(),
                        tolerance.alpha_rad,
                        max - attempt
                    ),
                });
            }
            context.record.outcome = Some(RunOutcome::Success { regrasps: attempt });
            Transition(State::done())
        } else if attempt < context.plan.max_regrasps {
            let sensor_old_from_new =
                t_corr_with_gain(&line, &context.plan.target, &context.plan.correction_gain);
            self.base_from_tcp_aim = self.base_from_tcp_grasped
                * context.plan.tcp_from_sensor
                * sensor_old_from_new
                * context.plan.tcp_from_sensor.inverse();
            Transition(State::regrasp())
        } else {
            fail(
                context,
                Failure::ToleranceNotReached {
                    regrasps: attempt,
                    error,
                },
            )
        }
    }

    fn after_transition(&mut self, source: &State, target: &State, context: &mut Context) {
        context.record.transitions.push(TransitionRecord {
            from: source.name(),
            to: target.name(),
            t_s: context.now_s,
        });
    }
}

/// The one table of names: each state's variant beside its handler, whose
/// name is the state's name in records, reports, breakpoints and the graph,
/// in the order of the sequence. `name`'s match is exhaustive, so a state
/// the machine gains does not compile until it is named here; a test checks
/// that each variant sits beside its own handler.
macro_rules! names {
    (
        states: $($variant:ident: $handler:ident),+;
        superstates: $($super_variant:ident: $super_handler:ident),+;
    ) => {
        impl State {
            /// Every state's name, in the order of the sequence.
            pub const NAMES: [&'static str; [$(stringify!($handler)),+].len()] =
                [$(stringify!($handler)),+];

            /// Every state, in the order of the sequence.
            pub fn all() -> [State; Self::NAMES.len()] {
                [$(State::$handler()),+]
            }

            /// The state's name, as records and reports spell it.
            pub fn name(&self) -> &'static str {
                match self {
                    $(State::$variant { .. } => stringify!($handler),)+
                }
            }
        }

        impl Superstate {
            /// The superstate's name, as the graph spells it.
            pub fn name(&self) -> &'static str {
                match self {
                    $(Superstate::$super_variant { .. } => stringify!($super_handler),)+
                }
            }
        }
    };
}

names! {
    states:
        Idle: idle,
        Prepare: prepare,
        Detect: detect,
        Approach: approach,
        TrialGrasp: trial_grasp,
        Search: search,
        Evaluate: evaluate,
        Regrasp: regrasp,
        Verify: verify,
        Done: done,
        Failed: failed,
        Fault: fault;
    superstates:
        Grasping: grasping;
}

impl State {
    /// The state called `name`, if there is one.
    pub fn named(name: &str) -> Option<State> {
        Self::all().into_iter().find(|state| state.name() == name)
    }

    /// The superstate that holds this state, if any.
    pub fn parent(&self) -> Option<Superstate> {
        statig::blocking::State::<GraspTask>::superstate(&mut self.clone())
    }

    /// Whether the run is over in this state.
    pub fn is_final(&self) -> bool {
        matches!(
            self,
            State::Done { .. } | State::Failed { .. } | State::Fault { .. }
        )
    }
}

fn fail(context: &mut Context, reason: Failure) -> Outcome<State> {
    context.record.outcome = Some(RunOutcome::Failed { reason });
    Transition(State::failed())
}

fn fault(
    context: &mut Context,
    device: Option<crate::hw::DeviceKind>,
    error: String,
) -> Outcome<State> {
    context.record.outcome = Some(RunOutcome::Fault {
        state: context
            .record
            .current_state()
            .unwrap_or(State::idle().name()),
        device,
        error,
    });
    Transition(State::fault())
}

#[cfg(test)]
mod tests {
    //! The machine alone, fed events by hand: no cell, no I/O.

    use nalgebra::{Isometry2, Translation3, UnitQuaternion, Vector2, Vector3};

    use super::*;
    use crate::detector::{CableDetection, Detections};
    use crate::geometry::{CorrectionGain, LineInSensor, PoseError};
    use crate::perception::tactile::{Estimator, FitConfig};
    use crate::sim::tactile_model::SimTactileConfig;
    use crate::sim::tactile_model::TactileModel;
    use crate::sim::{Stream, rng};

    fn plan(max_regrasps: u32, estimator: Estimator) -> Plan {
        let tcp_from_sensor = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, -10.0),
            UnitQuaternion::from_euler_angles(-std::f64::consts::FRAC_PI_2, 0.0, 0.0),
        );
        Plan {
            target: LineInSensor::new(0.0, 0.0),
            tolerance: PoseError {
                n_mm: 0.5,
                alpha_rad: 0.05,
            },
            standoff_mm: 50.0,
            speed_mm_s: 100.0,
            open_mm: 20.0,
            grip_current_a: 1.0,
            max_regrasps,
            retreat_mm: 30.0,
            correction_gain: CorrectionGain::PAPER,
            bias_frames: 50,
            average_frames: 4,
            fit: FitConfig {
                pitch_mm: 3.55,
                contact_threshold_v: 0.05,
            },
            estimator,
            tcp_from_sensor,
            prior: None,
            touch_only: false,
            view: crate::recording::CellView {
                tcp_from_sensor,
                tcp_from_marker: Isometry3::identity(),
                camera: None,
                pitch_mm: 3.55,
            },
        }
    }

    /// A plan with a prior at the base's origin, σ 10 mm across and
    /// 0.1 rad: its search tries 0, +10.65, −10.65, +21.3, −21.3 mm
    /// across, at most `max_moves` of them.
    fn searching_plan(touch_only: bool, max_moves: usize) -> Plan {
        Plan {
            prior: Some(Prior {
                base_from_cable: Isometry3::identity(),
                position_sigma_mm: 10.0,
                angle_sigma_rad: 0.1,
                max_moves,
            }),
            touch_only,
            ..plan(1, Estimator::Centroids)
        }
    }

    /// How far across the prior a grasp at `base_from_tcp` aims: with a
    /// zero target the pad's frame is the aimed cable frame, and the
    /// prior's is the base's.
    fn across_prior_mm(base_from_tcp: &Isometry3<f64>) -> f64 {
        let tcp_from_sensor = plan(1, Estimator::Centroids).tcp_from_sensor;
        (base_from_tcp * tcp_from_sensor).translation.vector.y
    }

    struct Harness {
        machine: statig::blocking::InitializedStateMachine<GraspTask>,
        context: Context,
        model: TactileModel,
    }

    impl Harness {
        fn new(max_regrasps: u32) -> Self {
            Self::with_estimator(max_regrasps, Estimator::Centroids)
        }

        fn with_estimator(max_regrasps: u32, estimator: Estimator) -> Self {
            Self::with_plan(plan(max_regrasps, estimator))
        }

        fn with_plan(plan: Plan) -> Self {
            let record = RunRecord::new("t", "c", 0, plan.target, plan.tolerance);
            let mut context = Context::new(plan, record);
            let machine = GraspTask::new()
                .uninitialized_state_machine()
                .init_with_context(&mut context);
            let noiseless = SimTactileConfig {
                line_spread_pitch: 0.55,
                span_v: 1.2,
                rest_v: [0.9, 1.5],
                gain_spread: 0.0,
                noise_fraction: 0.0,
                silent_after_frames: None,
            };
            let model =
                TactileModel::new(&noiseless, 3.55, &mut rng(0, Stream::TactileCalibration));
            Self {
                machine,
                context,
                model,
            }
        }

        fn feed(&mut self, event: Event) -> Option<Command> {
            self.machine.handle_with_context(&event, &mut self.context);
            self.context.command.take()
        }

        fn frames(&self, count: usize, pressed: Option<LineInSensor>) -> Event {
            let mut r = rng(1, Stream::Tactile);
            let raw = self.model.frame(pressed.map(|line| (line, 2.5)), &mut r);
            Event::Tactile {
                frames: vec![TactileFrame { t_s: 0.0, raw }; count],
                true_line: pressed,
            }
        }

        fn state(&self) -> State {
            *self.machine.state()
        }

        /// Start, bias, a detected cable at the origin, arrival.
        fn up_to_trial_grasp(&mut self) -> Command {
            assert!(matches!(
                self.feed(Event::Start),
                Some(Command::Prepare {
                    bias_frames: 50,
                    ..
                })
            ));
            let bias = self.frames(50, None);
            assert_eq!(self.feed(bias), Some(Command::Detect));
            let detection = CableDetection {
                base_from_cable: Isometry3::identity(),
                centre_line: Vec::new(),
                confidence: 1.0,
            };
            let moved = self.feed(Event::Detected(Detections {
                cables: vec![detection],
                image: None,
                skipped: Vec::new(),
            }));
            assert!(matches!(moved, Some(Command::MoveTo { .. })), "{moved:?}");
            self.feed(Event::Arrived).expect("grasp command")
        }

        /// Start and bias; with a touch-only plan, then also at the
        /// standoff of the search's first pose.
        fn up_to_detect_or_approach(&mut self) -> Option<Command> {
            self.feed(Event::Start);
            self.feed(self.frames(50, None))
        }

        fn grasped_nothing(&mut self) -> Option<Command> {
            self.feed(Event::Grasped {
                base_from_tcp: Isometry3::identity(),
                grip: GripOutcome::Empty,
            })
        }

        fn grasped_at(&mut self, base_from_tcp: Isometry3<f64>) -> Option<Command> {
            self.feed(Event::Grasped {
                base_from_tcp,
                grip: GripOutcome::Holding { opening_mm: 2.2 },
            })
        }
    }

    #[test]
    fn each_state_is_named_after_its_handler_once() {
        // `all` makes each state with its handler's constructor and
        // `NAMES` holds the handlers' names: each must be the name of the
        // variant the constructor makes.
        let names = State::all().map(|state| state.name());
        assert_eq!(names, State::NAMES);
        let unique: std::collections::BTreeSet<_> = names.iter().collect();
        assert_eq!(unique.len(), names.len());
        for state in State::all() {
            assert_eq!(State::named(state.name()), Some(state));
        }
        assert_eq!(State::named("trial grasp"), None);
        assert_eq!(
            State::prepare().parent().map(|s| s.name()),
            Some("grasping")
        );
        assert_eq!(State::idle().parent(), None);
    }

    #[test]
    fn the_trial_grasp_aims_the_pad_at_the_detected_cable() {
        let mut h = Harness::new(1);
        let Command::Grasp { base_from_tcp, .. } = h.up_to_trial_grasp() else {
            panic!("expected a grasp");
        };
        // With a zero target the sensor frame is the cable's frame.
        let base_from_sensor = base_from_tcp * plan(1, Estimator::Centroids).tcp_from_sensor;
        assert!((base_from_sensor.translation.vector).norm() < 1e-9);
        assert!(base_from_sensor.rotation.angle() < 1e-9);
        assert_eq!(h.state(), State::trial_grasp());
    }

    #[test]
    fn a_grasp_within_tolerance_is_done_without_regrasp() {
        let mut h = Harness::new(1);
        h.up_to_trial_grasp();
        assert!(matches!(
            h.grasped_at(Isometry3::identity()),
            Some(Command::ReadTactile { frames: 4 })
        ));
        let on_target = h.frames(4, Some(LineInSensor::new(0.0, 0.1)));
        assert_eq!(h.feed(on_target), None);
        assert_eq!(h.state(), State::done());
        assert!(matches!(
            h.context.record.outcome,
            Some(RunOutcome::Success { regrasps: 0 })
        ));
    }

    #[test]
    fn the_regrasp_aims_with_t_corr_from_the_measured_pose() {
        // The oracle estimate is exact, so the aim must be too.
        let mut h = Harness::with_estimator(1, Estimator::Oracle);
        h.up_to_trial_grasp();
        let grasped = Isometry3::from_parts(
            Translation3::new(400.0, 10.0, 300.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.4),
        );
        h.grasped_at(grasped);
        let truth = LineInSensor::new(0.15, -2.0);
        let Some(Command::Regrasp { base_from_tcp, .. }) = h.feed(h.frames(4, Some(truth))) else {
            panic!("expected a regrasp in {:?}", h.state());
        };
        // Where the true cable lies in the new pad frame: near the target.
        let tcp_from_sensor = plan(1, Estimator::Oracle).tcp_from_sensor;
        let old_from_new =
            (grasped * tcp_from_sensor).inverse() * (base_from_tcp * tcp_from_sensor);
        assert!(
            old_from_new.translation.vector.z.abs() < 1e-9,
            "stays in the pad's plane"
        );
        let (_, _, yaw) = old_from_new.rotation.euler_angles();
        let t = old_from_new.translation.vector;
        let new_from_old = Isometry2::new(Vector2::new(t.x, t.y), yaw).inverse();
        let error = truth
            .transformed(&new_from_old)
            .error_to(&LineInSensor::new(0.0, 0.0));
        assert!(
            error.n_mm.abs() < 0.2 && error.alpha_rad.abs() < 0.02,
            "{error:?}"
        );
        assert_eq!(h.state(), State::regrasp());
    }

    #[test]
    fn out_of_tolerance_after_the_last_regrasp_fails() {
        let mut h = Harness::new(1);
        h.up_to_trial_grasp();
        h.grasped_at(Isometry3::identity());
        let off = h.frames(4, Some(LineInSensor::new(0.2, 2.0)));
        assert!(matches!(h.feed(off.clone()), Some(Command::Regrasp { .. })));
        assert!(matches!(
            h.grasped_at(Isometry3::identity()),
            Some(Command::ReadTactile { .. })
        ));
        assert_eq!(h.state(), State::verify());
        assert_eq!(h.feed(off), None);
        assert_eq!(h.state(), State::failed());
        match &h.context.record.outcome {
            Some(RunOutcome::Failed {
                reason: Failure::ToleranceNotReached { regrasps: 1, error },
            }) => assert!(error.n_mm > 1.5),
            other => panic!("{other:?}"),
        }
        assert_eq!(h.context.record.grasps.len(), 2);
    }

    #[test]
    fn no_cable_on_the_pad_fails_with_its_peak() {
        let mut h = Harness::new(1);
        h.up_to_trial_grasp();
        h.grasped_at(Isometry3::identity());
        let empty = h.frames(4, None);
        h.feed(empty);
        assert_eq!(h.state(), State::failed());
        assert!(matches!(
            h.context.record.outcome,
            Some(RunOutcome::Failed {
                reason: Failure::NoContact { attempt: 0, .. }
            })
        ));
    }

    #[test]
    fn empty_jaws_and_no_detection_fail() {
        let mut h = Harness::new(1);
        h.up_to_trial_grasp();
        h.feed(Event::Grasped {
            base_from_tcp: Isometry3::identity(),
            grip: GripOutcome::Empty,
        });
        assert_eq!(h.state(), State::failed());

        let mut h = Harness::new(1);
        h.feed(Event::Start);
        h.feed(h.frames(50, None));
        h.feed(Event::Detected(Detections {
            cables: Vec::new(),
            image: None,
            skipped: Vec::new(),
        }));
        assert_eq!(h.state(), State::failed());
        assert!(matches!(
            h.context.record.outcome,
            Some(RunOutcome::Failed {
                reason: Failure::NothingDetected
            })
        ));
    }

    #[test]
    fn a_device_fault_in_any_step_leads_to_a_safe_stop() {
        let mut h = Harness::new(1);
        h.feed(Event::Start);
        h.feed(h.frames(50, None));
        h.feed(Event::Detected(Detections {
            cables: vec![CableDetection {
                base_from_cable: Isometry3::identity(),
                centre_line: Vec::new(),
                confidence: 1.0,
            }],
            image: None,
            skipped: Vec::new(),
        }));
        assert_eq!(h.state(), State::approach());
        let error = DeviceError::Timeout {
            device: DeviceKind::Arm,
            waited_ms: 500,
        };
        assert_eq!(
            h.feed(Event::DeviceFault(error)),
            Some(Command::SafeStop { open_mm: 20.0 })
        );
        assert_eq!(h.state(), State::fault());
        match &h.context.record.outcome {
            Some(RunOutcome::Fault { state, device, .. }) => {
                assert_eq!(*state, State::approach().name());
                assert_eq!(*device, Some(DeviceKind::Arm));
            }
            other => panic!("{other:?}"),
        }
        let stuck = DeviceError::Refused {
            device: DeviceKind::Gripper,
            command: "move_to",
            reason: "not referenced".into(),
        };
        assert_eq!(
            h.feed(Event::Stopped {
                problems: vec![stuck]
            }),
            None
        );
        assert_eq!(h.context.record.safe_stop_problems.len(), 1);
        assert_eq!(h.state(), State::fault());
    }

    #[test]
    fn abort_while_evaluating_stops_and_keeps_the_record() {
        let mut h = Harness::new(1);
        h.up_to_trial_grasp();
        h.grasped_at(Isometry3::identity());
        assert_eq!(h.state(), State::evaluate());
        assert!(matches!(
            h.feed(Event::Abort),
            Some(Command::SafeStop { .. })
        ));
        let states: Vec<_> = h.context.record.transitions.iter().map(|t| t.to).collect();
        let expected = [
            State::prepare(),
            State::detect(),
            State::approach(),
            State::trial_grasp(),
            State::evaluate(),
            State::fault(),
        ];
        assert_eq!(states, expected.map(|state| state.name()));
    }

    #[test]
    fn the_oracle_estimator_without_truth_fails_the_grasp() {
        let mut h = Harness::with_estimator(1, Estimator::Oracle);
        h.up_to_trial_grasp();
        h.grasped_at(Isometry3::identity());
        let Event::Tactile { frames, .. } = h.frames(4, Some(LineInSensor::new(0.0, 1.0))) else {
            unreachable!("frames() makes a tactile event");
        };
        h.feed(Event::Tactile {
            frames,
            true_line: None,
        });
        assert_eq!(h.state(), State::failed());
        assert!(matches!(
            &h.context.record.outcome,
            Some(RunOutcome::Failed {
                reason: Failure::FitFailed { attempt: 0, .. }
            })
        ));
    }

    #[test]
    fn too_few_bias_frames_is_a_fault() {
        let mut h = Harness::new(1);
        h.feed(Event::Start);
        h.feed(h.frames(10, None));
        assert_eq!(h.state(), State::fault());
    }

    #[test]
    fn without_a_detection_a_prior_starts_a_search_at_its_mean() {
        let mut h = Harness::with_plan(searching_plan(false, 5));
        assert_eq!(h.up_to_detect_or_approach(), Some(Command::Detect));
        let moved = h.feed(Event::Detected(Detections {
            cables: Vec::new(),
            image: None,
            skipped: Vec::new(),
        }));
        assert!(matches!(moved, Some(Command::MoveTo { .. })), "{moved:?}");
        let Some(Command::Grasp { base_from_tcp, .. }) = h.feed(Event::Arrived) else {
            panic!("expected the trial grasp in {:?}", h.state());
        };
        assert!(across_prior_mm(&base_from_tcp).abs() < 1e-9);
        let touch_only = h.context.record.touch_only.as_ref().expect("searching");
        assert_eq!(touch_only.why, WhyTouchOnly::NoCableDetected);
        assert_eq!(touch_only.search_moves, 1);
    }

    #[test]
    fn a_touch_only_plan_does_not_look() {
        let mut h = Harness::with_plan(searching_plan(true, 5));
        let moved = h.up_to_detect_or_approach();
        assert!(matches!(moved, Some(Command::MoveTo { .. })), "{moved:?}");
        assert_eq!(h.state(), State::approach());
        let why = h.context.record.touch_only.as_ref().map(|t| &t.why);
        assert_eq!(why, Some(&WhyTouchOnly::Forced));
    }

    #[test]
    fn the_search_steps_across_until_the_pad_feels_the_cable_then_judges_that_grasp() {
        let mut h = Harness::with_plan(searching_plan(true, 5));
        h.up_to_detect_or_approach();
        assert!(matches!(
            h.feed(Event::Arrived),
            Some(Command::Grasp { .. })
        ));
        // The jaws close on nothing: on to the next pose, one step up.
        let Some(Command::Probe { base_from_tcp, .. }) = h.grasped_nothing() else {
            panic!("expected a probe in {:?}", h.state());
        };
        assert_eq!(h.state(), State::search());
        assert!((across_prior_mm(&base_from_tcp) - 10.65).abs() < 1e-9);
        // They hold something the pad does not feel: a miss, then a step
        // down.
        assert!(matches!(
            h.grasped_at(Isometry3::identity()),
            Some(Command::ReadTactile { .. })
        ));
        let Some(Command::Probe { base_from_tcp, .. }) = h.feed(h.frames(4, None)) else {
            panic!("expected a probe in {:?}", h.state());
        };
        assert!((across_prior_mm(&base_from_tcp) + 10.65).abs() < 1e-9);
        // The pad feels the cable on target: the search's trial grasp.
        h.grasped_at(Isometry3::identity());
        assert_eq!(h.feed(h.frames(4, Some(LineInSensor::new(0.0, 0.1)))), None);
        assert_eq!(h.state(), State::done());
        let record = &h.context.record;
        assert!(matches!(
            record.outcome,
            Some(RunOutcome::Success { regrasps: 0 })
        ));
        let touch_only = record.touch_only.as_ref().expect("searched");
        assert_eq!(touch_only.search_moves, 3);
        assert_eq!(touch_only.misses.len(), 1);
        assert_eq!(record.grasps.len(), 1);
        let states: Vec<_> = record.transitions.iter().map(|t| t.to).collect();
        let expected = [
            State::prepare(),
            State::approach(),
            State::trial_grasp(),
            State::search(),
            State::evaluate(),
            State::search(),
            State::evaluate(),
            State::done(),
        ];
        assert_eq!(states, expected.map(|state| state.name()));
    }

    #[test]
    fn a_search_that_feels_nothing_fails_after_its_last_move() {
        let mut h = Harness::with_plan(searching_plan(true, 3));
        h.up_to_detect_or_approach();
        h.feed(Event::Arrived);
        assert!(matches!(h.grasped_nothing(), Some(Command::Probe { .. })));
        assert!(matches!(h.grasped_nothing(), Some(Command::Probe { .. })));
        assert_eq!(h.grasped_nothing(), None);
        assert_eq!(h.state(), State::failed());
        let Some(RunOutcome::Failed { reason }) = &h.context.record.outcome else {
            panic!("{:?}", h.context.record.outcome);
        };
        let Failure::SearchExhausted {
            search_moves,
            covered_across_mm,
            position_sigma_mm,
            ..
        } = reason
        else {
            panic!("{reason:?}");
        };
        assert_eq!((*search_moves, *position_sigma_mm), (3, 10.0));
        // ±10.65 mm and the pad's ±7.1 mm band.
        assert!((covered_across_mm - 17.75).abs() < 1e-9);
        assert!(
            reason
                .to_string()
                .starts_with("no cable felt in 3 search move(s)")
        );
    }

    #[test]
    fn an_unusable_detector_leads_to_a_search_with_a_prior_and_a_fault_without() {
        let unusable = DeviceError::Unusable {
            device: DeviceKind::Detector,
            reason: "the model is missing".into(),
        };
        let mut h = Harness::with_plan(searching_plan(false, 5));
        h.up_to_detect_or_approach();
        let moved = h.feed(Event::DeviceFault(unusable.clone()));
        assert!(matches!(moved, Some(Command::MoveTo { .. })), "{moved:?}");
        match h.context.record.touch_only.as_ref().map(|t| &t.why) {
            Some(WhyTouchOnly::DetectorUnusable { error }) => {
                assert!(error.contains("the model is missing"), "{error}");
            }
            other => panic!("{other:?}"),
        }
        let mut h = Harness::new(1);
        h.up_to_detect_or_approach();
        h.feed(Event::DeviceFault(unusable));
        assert_eq!(h.state(), State::fault());
        // Another device's fault while detecting stays a fault.
        let mut h = Harness::with_plan(searching_plan(false, 5));
        h.up_to_detect_or_approach();
        h.feed(Event::DeviceFault(DeviceError::Timeout {
            device: DeviceKind::Arm,
            waited_ms: 500,
        }));
        assert_eq!(h.state(), State::fault());
        assert!(h.context.record.touch_only.is_none());
    }
}
