//! The Franka Panda through `franka_rust`, which speaks libfranka's
//! protocol: commands over TCP (port 1337) and the 1 kHz stream of states
//! and commands over UDP.
//!
//! `franka_rust` blocks without a deadline (a controller that stops
//! answering would hang the caller), and panics when it cannot connect. So
//! the connection lives on a thread of its own, every call waits for it
//! with a deadline, and a call that misses its deadline drops the
//! connection: the next call connects afresh. The controller itself stops
//! the arm within a few cycles when its client falls silent (a
//! communication reflex). Connecting is lazy, on the first call.

use std::net::{TcpStream, ToSocketAddrs};
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, mpsc};
use std::time::Duration;

use franka_rust::{FrankaPanda, PORT_ROBOT_COMMAND};
use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion};
use robot_behavior::behavior::{CartesianPoseControl, Control, Robot};
use robot_behavior::{Pose, RobotException};
use rsruckig::prelude::{DataArrayOrVec, Trajectory};

use super::Arm;
use crate::hw::{DeviceError, DeviceKind};
use crate::sim::motion::{CartesianLimits, straight_line_profile};

/// How long connecting (TCP connect and the protocol's handshake) may take.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(3);
/// How long one request (a state, a stop, a recovery) may take. A move may
/// take as long as it makes progress: it fails once no control cycle has
/// passed for this long.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(2);
/// How many reads after a recovery may still see states sent before it.
const RECOVERY_READS: usize = 1000;
/// A pose from the controller is a rigid transform to within this.
const RIGID_TOLERANCE: f64 = 1e-6;

/// The Panda's published Cartesian limits (libfranka's documentation, as
/// `franka_rust` states them in m and rad), each scaled by `fraction` for
/// the profiles this driver plans.
pub fn panda_limits(fraction: f64) -> CartesianLimits {
    use robot_behavior::EndPoint;
    CartesianLimits {
        accel_mm_s2: FrankaPanda::CARTESIAN_ACC_BOUND * 1000.0 * fraction,
        jerk_mm_s3: FrankaPanda::CARTESIAN_JERK_BOUND * 1000.0 * fraction,
        angular_speed_rad_s: FrankaPanda::ROTATION_VEL_BOUND * fraction,
        angular_accel_rad_s2: FrankaPanda::ROTATION_ACC_BOUND * fraction,
        angular_jerk_rad_s3: FrankaPanda::ROTATION_JERK_BOUND * fraction,
    }
}

/// The pose a libfranka pose stands for (a 4×4 homogeneous matrix, column
/// major, in metres), in mm; `None` unless it is a rigid transform.
pub fn isometry_from_franka(pose_m: &[f64; 16]) -> Option<Isometry3<f64>> {
    if !pose_m.iter().all(|x| x.is_finite()) {
        return None;
    }
    let matrix = Matrix4::from_column_slice(pose_m);
    let last_row_ok = (matrix[(3, 0)].abs() + matrix[(3, 1)].abs() + matrix[(3, 2)].abs())
        < RIGID_TOLERANCE
        && (matrix[(3, 3)] - 1.0).abs() < RIGID_TOLERANCE;
    let rotation: Matrix3<f64> = matrix.fixed_view::<3, 3>(0, 0).into_owned();
    let orthonormal = (rotation.transpose() * rotation - Matrix3::identity()).norm()
        < RIGID_TOLERANCE
        && rotation.determinant() > 0.0;
    if !(last_row_ok && orthonormal) {
        return None;
    }
    let translation_mm = matrix.fixed_view::<3, 1>(0, 3) * 1000.0;
    Some(Isometry3::from_parts(
        Translation3::from(translation_mm.into_owned()),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rotation)),
    ))
}

/// A pose in mm as libfranka takes it: a 4×4 homogeneous matrix, column
/// major, in metres.
pub fn franka_from_isometry(pose_mm: &Isometry3<f64>) -> [f64; 16] {
    let mut matrix = pose_mm.to_homogeneous();
    for row in 0..3 {
        matrix[(row, 3)] /= 1000.0;
    }
    let mut pose_m = [0.0; 16];
    pose_m.copy_from_slice(matrix.as_slice());
    pose_m
}

/// The pose at `fraction_translation` of the straight line from `from` to
/// `to` and `fraction_rotation` of the rotation between them (about one
/// fixed axis).
pub fn interpolate(
    from: &Isometry3<f64>,
    to: &Isometry3<f64>,
    fraction_translation: f64,
    fraction_rotation: f64,
) -> Isometry3<f64> {
    let translation = from
        .translation
        .vector
        .lerp(&to.translation.vector, fraction_translation);
    let turn = from.rotation.inverse() * to.rotation;
    Isometry3::from_parts(
        Translation3::from(translation),
        from.rotation * UnitQuaternion::from_scaled_axis(turn.scaled_axis() * fraction_rotation),
    )
}

/// What a call on the connection's thread does.
type Job = Box<dyn FnOnce(&mut FrankaPanda) + Send>;

/// A connection to the controller, served by its own thread.
struct Session {
    jobs: mpsc::Sender<Job>,
    /// Collision thresholds and impedances are set before the first move
    /// of a session, not on connecting: a controller in reflex refuses
    /// them, and recovery needs a connection first.
    configured: bool,
}

/// The Franka Panda: the TCP pose in the base frame, straight-line moves
/// with jerk-limited profiles streamed at 1 kHz, stop, and recovery from
/// reflexes.
pub struct Panda {
    address: String,
    /// The TCP in the end-effector frame the controller reports (`EE`, set
    /// in Desk).
    ee_from_tcp: Isometry3<f64>,
    limits: CartesianLimits,
    session: Option<Session>,
}

impl Panda {
    /// A Panda at `address` (host name or IP; the port is the protocol's).
    /// Nothing is sent until the first call.
    pub fn new(address: &str, ee_from_tcp: Isometry3<f64>, limits: CartesianLimits) -> Self {
        Self {
            address: address.to_owned(),
            ee_from_tcp,
            limits,
            session: None,
        }
    }

    fn endpoint(&self) -> String {
        format!("{}:{PORT_ROBOT_COMMAND}", self.address)
    }

    fn disconnected(&self, reason: String) -> DeviceError {
        DeviceError::Disconnected {
            device: DeviceKind::Arm,
            port: self.endpoint(),
            reason,
        }
    }

    /// The device error for what `franka_rust` reported.
    fn device_error(&self, command: &'static str, error: RobotException) -> DeviceError {
        match error {
            RobotException::NetworkError(reason) => self.disconnected(reason),
            RobotException::DeserializeError(detail) => DeviceError::Garbled {
                device: DeviceKind::Arm,
                port: self.endpoint(),
                detail,
            },
            other => DeviceError::Refused {
                device: DeviceKind::Arm,
                command,
                reason: format!(
                    "{other}; if the controller reports an error or reflex, clear its cause, \
                     then recover (`cablecell device arm --address {} recover`)",
                    self.address
                ),
            },
        }
    }

    /// Opens a connection: checks that the controller listens (a clear
    /// error rather than `franka_rust`'s panic), then lets `franka_rust`
    /// connect on the session's thread.
    fn connect(&self) -> Result<Session, DeviceError> {
        let endpoint = self.endpoint();
        let socket_address = endpoint
            .to_socket_addrs()
            .map_err(|e| self.disconnected(format!("cannot resolve the address: {e}")))?
            .next()
            .ok_or_else(|| self.disconnected("the address resolves to nothing".into()))?;
        TcpStream::connect_timeout(&socket_address, CONNECT_TIMEOUT).map_err(|e| {
            self.disconnected(format!(
                "cannot connect: {e} (is the controller on, FCI activated in Desk, the address right?)"
            ))
        })?;
        let (jobs, job_queue) = mpsc::channel::<Job>();
        let (ready, connected) = mpsc::channel::<Result<(), String>>();
        let address = self.address.clone();
        std::thread::Builder::new()
            .name("panda".into())
            .spawn(move || {
                // franka_rust panics when the handshake fails (a refused
                // protocol version, a connection closed on it).
                let robot =
                    std::panic::catch_unwind(AssertUnwindSafe(|| FrankaPanda::new(&address)));
                let mut robot = match robot {
                    Ok(robot) => robot,
                    Err(panic) => {
                        let reason = panic
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                            .unwrap_or_else(|| "franka_rust gave up".into());
                        let _ = ready.send(Err(reason));
                        return;
                    }
                };
                let _ = ready.send(Ok(()));
                for job in job_queue {
                    job(&mut robot);
                }
            })
            .map_err(|e| self.disconnected(format!("cannot start the connection's thread: {e}")))?;
        match connected.recv_timeout(CONNECT_TIMEOUT) {
            Ok(Ok(())) => Ok(Session {
                jobs,
                configured: false,
            }),
            Ok(Err(reason)) => Err(self.disconnected(format!("handshake failed: {reason}"))),
            Err(mpsc::RecvTimeoutError::Timeout) => Err(DeviceError::Timeout {
                device: DeviceKind::Arm,
                waited_ms: CONNECT_TIMEOUT.as_millis() as u64,
            }),
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                Err(self.disconnected("the connection's thread ended".into()))
            }
        }
    }

    /// Runs `job` on the connection (connecting first if there is none),
    /// waiting for as long as `progress` (which the job advances) moves on
    /// within each `timeout`, or `timeout` alone without it; a missed
    /// deadline or a lost connection drops the connection.
    fn call<T: Send + 'static>(
        &mut self,
        command: &'static str,
        timeout: Duration,
        progress: Option<Arc<AtomicU64>>,
        job: impl FnOnce(&mut FrankaPanda) -> Result<T, RobotException> + Send + 'static,
    ) -> Result<T, DeviceError> {
        let session = match self.session.take() {
            Some(session) => session,
            None => self.connect()?,
        };
        let (reply, answer) = mpsc::channel();
        let sent = session.jobs.send(Box::new(move |robot: &mut FrankaPanda| {
            let _ = reply.send(job(robot));
        }));
        if sent.is_err() {
            return Err(self.disconnected("the connection's thread ended".into()));
        }
        let mut answered = answer.recv_timeout(timeout);
        let mut progress_seen = 0;
        while let (Err(mpsc::RecvTimeoutError::Timeout), Some(progress)) = (&answered, &progress) {
            let now = progress.load(Ordering::Relaxed);
            if now == progress_seen {
                break;
            }
            progress_seen = now;
            answered = answer.recv_timeout(timeout);
        }
        match answered {
            Ok(Ok(value)) => {
                self.session = Some(session);
                Ok(value)
            }
            Ok(Err(error)) => {
                // The connection stays unless the link itself failed.
                let error = self.device_error(command, error);
                if !matches!(error, DeviceError::Disconnected { .. }) {
                    self.session = Some(session);
                }
                Err(error)
            }
            Err(mpsc::RecvTimeoutError::Timeout) => Err(DeviceError::Timeout {
                device: DeviceKind::Arm,
                waited_ms: timeout.as_millis() as u64,
            }),
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                Err(self.disconnected("the connection's thread ended".into()))
            }
        }
    }

    /// The measured and the desired pose of the end effector in the base
    /// frame (libfranka's `O_T_EE` and `O_T_EE_d`), in mm.
    fn base_from_ee(&mut self) -> Result<(Isometry3<f64>, Isometry3<f64>), DeviceError> {
        let (measured, desired) = self.call("read state", REQUEST_TIMEOUT, None, |robot| {
            robot
                .read_franka_state()
                .map(|state| (state.pose_o_to_ee, state.pose_o_to_ee_d))
        })?;
        let garbled = |what: &str| DeviceError::Garbled {
            device: DeviceKind::Arm,
            port: self.endpoint(),
            detail: format!("{what} is not a rigid transform"),
        };
        Ok((
            isometry_from_franka(&measured).ok_or_else(|| garbled("O_T_EE"))?,
            isometry_from_franka(&desired).ok_or_else(|| garbled("O_T_EE_d"))?,
        ))
    }

    /// Clears the controller's errors after a reflex (a collision, a limit)
    /// with libfranka's automatic error recovery, on a fresh connection: a
    /// session whose motion a reflex aborted cannot start another.
    pub fn recover(&mut self) -> Result<(), DeviceError> {
        self.session = None;
        self.call("automatic error recovery", REQUEST_TIMEOUT, None, |robot| {
            robot.automatic_error_recovery()?;
            // franka_rust refuses a read when any queued state reports an
            // error, and states sent before the recovery still do: read
            // until a clean one arrives (each read consumes some).
            let mut result = robot.read_franka_state();
            for _ in 0..RECOVERY_READS {
                if result.is_ok() {
                    break;
                }
                result = robot.read_franka_state();
            }
            result.map(|_| ())
        })
    }

    fn refuse(&self, reason: String) -> DeviceError {
        DeviceError::Refused {
            device: DeviceKind::Arm,
            command: "move_linear",
            reason,
        }
    }
}

/// Distance (mm) and angle (rad) of `profile` at `time_s`.
fn sample(profile: &Trajectory<2>, time_s: f64) -> (f64, f64) {
    let mut position = DataArrayOrVec::Stack([0.0; 2]);
    profile.at_time(
        time_s.min(profile.get_duration()),
        &mut Some(&mut position),
        &mut None,
        &mut None,
        &mut None,
        &mut None,
    );
    (position[0], position[1])
}

impl Arm for Panda {
    fn base_from_tcp(&mut self) -> Result<Isometry3<f64>, DeviceError> {
        let (measured, _) = self.base_from_ee()?;
        Ok(measured * self.ee_from_tcp)
    }

    /// Plans a jerk-limited straight line of the TCP from the pose the
    /// controller holds to the target and streams the end effector's poses
    /// along it, one per 1 ms cycle of the controller's clock.
    fn move_linear(
        &mut self,
        base_from_tcp: &Isometry3<f64>,
        speed_mm_s: f64,
    ) -> Result<(), DeviceError> {
        // The line is the TCP's; the controller takes the end effector's
        // pose.
        let (_, from_ee) = self.base_from_ee()?;
        let from = from_ee * self.ee_from_tcp;
        let to = *base_from_tcp;
        let tcp_from_ee = self.ee_from_tcp.inverse();
        let distance_mm = (to.translation.vector - from.translation.vector).norm();
        let angle_rad = from.rotation.angle_to(&to.rotation);
        let profile = straight_line_profile(distance_mm, angle_rad, speed_mm_s, &self.limits)
            .ok_or_else(|| {
                self.refuse(format!(
                    "no jerk-limited profile for {distance_mm} mm and {angle_rad} rad"
                ))
            })?;
        let duration_s = profile.get_duration();
        let needs_configuring = !self.session.as_ref().is_some_and(|s| s.configured);
        let cycles = Arc::new(AtomicU64::new(0));
        let cycles_done = cycles.clone();
        let result = self.call("move_linear", REQUEST_TIMEOUT, Some(cycles), move |robot| {
            if needs_configuring {
                robot.set_default_behavior()?;
            }
            let mut elapsed_s = 0.0;
            robot.control_with::<CartesianPoseControl<7>, _>(move |_, period| {
                cycles_done.fetch_add(1, Ordering::Relaxed);
                elapsed_s += period.as_secs_f64();
                let (along_mm, turned_rad) = sample(&profile, elapsed_s);
                let fraction = |done: f64, total: f64| if total > 0.0 { done / total } else { 1.0 };
                let pose = interpolate(
                    &from,
                    &to,
                    fraction(along_mm, distance_mm),
                    fraction(turned_rad, angle_rad),
                );
                (
                    Pose::Homo(franka_from_isometry(&(pose * tcp_from_ee))),
                    elapsed_s >= duration_s,
                )
            })
        });
        match result {
            Ok(()) => {
                if let Some(session) = &mut self.session {
                    session.configured = true;
                }
                Ok(())
            }
            Err(error) => {
                // franka_rust refuses a new motion on a session whose last
                // one it could not confirm finished.
                self.session = None;
                Err(error)
            }
        }
    }

    /// Moves are synchronous, so none of this driver's runs when this is
    /// called; it stops a motion the controller still runs (one whose call
    /// timed out), connecting if need be. A controller in reflex has
    /// already stopped the arm.
    fn stop(&mut self) -> Result<(), DeviceError> {
        self.call("stop", REQUEST_TIMEOUT, None, |robot| {
            match robot.is_moving() {
                Ok(true) => robot.stop(),
                Ok(false) => Ok(()),
                Err(RobotException::CommandException(_)) => Ok(()),
                Err(error) => Err(error),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::Vector3;

    fn pose() -> Isometry3<f64> {
        Isometry3::new(
            Vector3::new(400.0, -50.0, 300.0),
            Vector3::new(3.0, 0.2, -0.4),
        )
    }

    #[test]
    fn franka_poses_round_trip_in_metres() {
        let pose_m = franka_from_isometry(&pose());
        // Column major: the translation is the fourth column, in metres.
        assert_relative_eq!(pose_m[12], 0.4, epsilon = 1e-12);
        assert_relative_eq!(pose_m[13], -0.05, epsilon = 1e-12);
        assert_relative_eq!(pose_m[14], 0.3, epsilon = 1e-12);
        assert_eq!(pose_m[15], 1.0);
        let back = isometry_from_franka(&pose_m).expect("rigid");
        assert_relative_eq!(back, pose(), epsilon = 1e-9);
    }

    #[test]
    fn a_matrix_that_is_not_rigid_is_refused() {
        let mut pose_m = franka_from_isometry(&pose());
        pose_m[0] *= 1.01;
        assert!(isometry_from_franka(&pose_m).is_none());
        let mut pose_m = franka_from_isometry(&pose());
        pose_m[3] = 0.5;
        assert!(isometry_from_franka(&pose_m).is_none());
        assert!(isometry_from_franka(&[f64::NAN; 16]).is_none());
        assert!(isometry_from_franka(&[0.0; 16]).is_none());
    }

    #[test]
    fn interpolation_runs_from_start_to_target_along_a_line() {
        let from = pose();
        let to = Isometry3::new(
            Vector3::new(420.0, -50.0, 290.0),
            Vector3::new(2.9, 0.3, -0.4),
        );
        assert_relative_eq!(interpolate(&from, &to, 0.0, 0.0), from, epsilon = 1e-12);
        assert_relative_eq!(interpolate(&from, &to, 1.0, 1.0), to, epsilon = 1e-9);
        let half = interpolate(&from, &to, 0.5, 0.5);
        assert_relative_eq!(
            half.translation.vector,
            Vector3::new(410.0, -50.0, 295.0),
            epsilon = 1e-9
        );
        let turned = from.rotation.angle_to(&half.rotation);
        assert_relative_eq!(
            turned,
            from.rotation.angle_to(&to.rotation) / 2.0,
            epsilon = 1e-9
        );
    }
}
