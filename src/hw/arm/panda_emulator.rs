//! A loopback emulator of the Panda's controller: libfranka's protocol
//! (version 5, the one `franka_rust` speaks) on TCP port 1337 and UDP, its
//! messages encoded with `franka_rust`'s own protocol types.
//!
//! It answers the handshake, streams the robot's state at 1 kHz to the
//! client's UDP port, runs Cartesian pose motions (the arm follows every
//! commanded pose exactly, and a motion ends when the client says it is
//! finished), stops, recovers from errors, and can be told to trigger a
//! Cartesian reflex during the next motion or to fall silent. During a
//! motion it waits for each cycle's command before sending the next state
//! (up to [`COMMAND_WAIT`]), so that a loaded test machine does not look
//! like a lossy network (a real controller would count such cycles lost and
//! the client's rate limiter would bend the path); the time the client sees
//! is the controller's clock, one message per millisecond.
//!
//! Bind it to a loopback address of its own (127.0.0.2, 127.0.0.3, ...):
//! the protocol's port is fixed.

use std::io::{self, Read, Write};
use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use franka_rust::types::robot_command::RobotCommand;
use franka_rust::types::robot_error::FrankaError;
use franka_rust::types::robot_state::{
    ControllerMode, MotionGeneratorMode, RobotMode, RobotStateInter,
};
use franka_rust::types::robot_types::{
    Command, ConnectStatusEnum, GetterSetterStatus, MoveStatus, StopMoveStatus,
};
use franka_rust::{FRANKA_ROBOT_VERSION, PORT_ROBOT_COMMAND};
use nalgebra::Isometry3;
use serde::Serialize;

use crate::hw::arm::panda::{franka_from_isometry, isometry_from_franka};
use crate::hw::nothing_arrived;

/// How long the emulator waits for the command of a motion's cycle before
/// counting it lost: long, so that a slow test machine loses none and the
/// emulated motion is the same on any machine.
pub const COMMAND_WAIT: Duration = Duration::from_millis(500);
/// The controller's cycle.
const CYCLE_S: f64 = 0.001;
/// How often blocked reads look at the stop flag.
const POLL: Duration = Duration::from_millis(20);
/// A libfranka command header: command, command id, total size (u32 each).
const HEADER_BYTES: usize = 12;
/// `MoveMotionGeneratorMode::CartesianPosition` on the wire.
const MOVE_CARTESIAN_POSITION: u32 = 2;
/// `MoveControllerMode::CartesianImpedance` and `ExternalController`.
const MOVE_CARTESIAN_IMPEDANCE: u32 = 1;
const MOVE_EXTERNAL_CONTROLLER: u32 = 2;

/// What the emulated controller did, for tests to check.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Report {
    /// Clients that completed the handshake.
    pub handshakes: u32,
    pub motions_finished: u32,
    pub motions_aborted: u32,
    pub recoveries: u32,
    /// Cycles in which a motion's command arrived.
    pub commanded_cycles: u64,
    /// The highest commanded end-effector speed over all motions.
    pub peak_speed_mm_s: f64,
}

type Writer = Arc<Mutex<TcpStream>>;

struct Motion {
    command_id: u32,
    reply_to: Writer,
    connection: u32,
    cycles: u64,
}

/// The controller's state, shared by the command connection's threads and
/// the 1 kHz loop.
struct Controller {
    base_from_ee: Isometry3<f64>,
    /// Commanded twist (m/s, rad/s) and its rate, as the state reports them.
    velocity: [f64; 6],
    acceleration: [f64; 6],
    motion: Option<Motion>,
    controller_mode: ControllerMode,
    errors: [bool; 41],
    reflex_after_cycles: Option<u64>,
    silent: bool,
    /// The connection that shook hands last, and its UDP address.
    client: Option<(u32, SocketAddr)>,
    message_id: u64,
    report: Report,
}

impl Controller {
    /// Whether an error (a reflex not yet recovered) is active.
    fn in_error(&self) -> bool {
        self.errors.iter().any(|&e| e)
    }

    fn state(&self) -> RobotStateInter {
        let pose_m = franka_from_isometry(&self.base_from_ee);
        let identity = franka_from_isometry(&Isometry3::identity());
        let mut state = RobotStateInter {
            message_id: self.message_id,
            O_T_EE: pose_m,
            O_T_EE_d: pose_m,
            O_T_EE_c: pose_m,
            F_T_EE: identity,
            F_T_NE: identity,
            NE_T_EE: identity,
            EE_T_K: identity,
            O_dP_EE_d: self.velocity,
            O_dP_EE_c: self.velocity,
            O_ddP_EE_c: self.acceleration,
            errors: self.errors,
            reflex_reason: self.errors,
            ..RobotStateInter::default()
        };
        if self.motion.is_some() {
            state.motion_generator_mode = MotionGeneratorMode::CartesianPosition;
            state.controller_mode = self.controller_mode;
            state.robot_mode = RobotMode::Move;
            state.control_command_success_rate = 1.0;
        } else if self.in_error() {
            state.robot_mode = RobotMode::Reflux;
        }
        state
    }

    /// Ends the running motion, answering its Move request with `status`.
    fn end_motion(&mut self, status: MoveStatus) {
        self.velocity = [0.0; 6];
        self.acceleration = [0.0; 6];
        if let Some(motion) = self.motion.take() {
            if status == MoveStatus::Success {
                self.report.motions_finished += 1;
            } else {
                self.report.motions_aborted += 1;
            }
            // A client that has gone cannot be answered.
            let _ = respond(
                &motion.reply_to,
                Command::Move,
                motion.command_id,
                status as u8,
            );
        }
    }

    fn reflex(&mut self, error: FrankaError, status: MoveStatus) {
        self.errors[error as usize] = true;
        self.end_motion(status);
    }

    /// Applies the client's command for the cycle of `message_id`.
    fn apply(&mut self, command: &RobotCommand) {
        let Some(motion) = &mut self.motion else {
            return;
        };
        if command.message_id != self.message_id {
            return;
        }
        motion.cycles += 1;
        self.report.commanded_cycles += 1;
        if self
            .reflex_after_cycles
            .is_some_and(|after| motion.cycles >= after)
        {
            self.reflex_after_cycles = None;
            self.reflex(FrankaError::CartesianReflex, MoveStatus::ReflexAborted);
            return;
        }
        let motion_command = command.motion;
        let Some(next) = isometry_from_franka(&{ motion_command.pose_o_to_ee_c }) else {
            self.reflex(
                FrankaError::CartesianPositionMotionGeneratorInvalidFrame,
                MoveStatus::Aborted,
            );
            return;
        };
        let linear_m_s =
            (next.translation.vector - self.base_from_ee.translation.vector) / 1000.0 / CYCLE_S;
        let angular_rad_s =
            (next.rotation * self.base_from_ee.rotation.inverse()).scaled_axis() / CYCLE_S;
        let velocity = [
            linear_m_s.x,
            linear_m_s.y,
            linear_m_s.z,
            angular_rad_s.x,
            angular_rad_s.y,
            angular_rad_s.z,
        ];
        self.acceleration = std::array::from_fn(|k| (velocity[k] - self.velocity[k]) / CYCLE_S);
        self.velocity = velocity;
        self.report.peak_speed_mm_s = self.report.peak_speed_mm_s.max(linear_m_s.norm() * 1000.0);
        self.base_from_ee = next;
        if motion_command.motion_generation_finished {
            self.end_motion(MoveStatus::Success);
        }
    }
}

/// The emulated controller, serving until dropped.
pub struct PandaEmulator {
    controller: Arc<Mutex<Controller>>,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

fn lock(controller: &Mutex<Controller>) -> MutexGuard<'_, Controller> {
    // A panicking emulator thread is a bug the tests will show; its data
    // stays usable.
    controller
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl PandaEmulator {
    /// Serves on `ip` (TCP port 1337, UDP from a free port) with the end
    /// effector at `base_from_ee` (mm).
    pub fn start(ip: IpAddr, base_from_ee: Isometry3<f64>) -> io::Result<Self> {
        let listener = TcpListener::bind((ip, PORT_ROBOT_COMMAND))?;
        listener.set_nonblocking(true)?;
        let udp = UdpSocket::bind((ip, 0))?;
        udp.set_read_timeout(Some(COMMAND_WAIT))?;
        let controller = Arc::new(Mutex::new(Controller {
            base_from_ee,
            velocity: [0.0; 6],
            acceleration: [0.0; 6],
            motion: None,
            controller_mode: ControllerMode::JointImpedance,
            errors: [false; 41],
            reflex_after_cycles: None,
            silent: false,
            client: None,
            message_id: 0,
            report: Report::default(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let threads = vec![
            {
                let (controller, stop) = (controller.clone(), stop.clone());
                std::thread::spawn(move || accept(&listener, &controller, &stop))
            },
            {
                let (controller, stop) = (controller.clone(), stop.clone());
                std::thread::spawn(move || stream_states(&udp, &controller, &stop))
            },
        ];
        Ok(Self {
            controller,
            stop,
            threads,
        })
    }

    /// Where the end effector is now.
    pub fn base_from_ee(&self) -> Isometry3<f64> {
        lock(&self.controller).base_from_ee
    }

    /// The next motion ends in a Cartesian reflex (a collision) once
    /// `after_cycles` of its commands have arrived.
    pub fn reflex_during_next_motion(&self, after_cycles: u64) {
        lock(&self.controller).reflex_after_cycles = Some(after_cycles);
    }

    /// Stops (or resumes) sending states, as a controller whose network
    /// link failed. Once it returns, no further state is sent; those sent
    /// before may still wait in the client's socket.
    pub fn set_silent(&self, silent: bool) {
        lock(&self.controller).silent = silent;
    }

    /// Whether the controller reports an error (a reflex not yet recovered).
    pub fn has_errors(&self) -> bool {
        lock(&self.controller).in_error()
    }

    pub fn report(&self) -> Report {
        lock(&self.controller).report
    }
}

impl Drop for PandaEmulator {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for thread in self.threads.drain(..) {
            let _ = thread.join();
        }
    }
}

fn accept(listener: &TcpListener, controller: &Arc<Mutex<Controller>>, stop: &Arc<AtomicBool>) {
    let mut connections = Vec::new();
    let mut next_id = 0;
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, peer)) => {
                next_id += 1;
                let (controller, stop, id) = (controller.clone(), stop.clone(), next_id);
                connections.push(std::thread::spawn(move || {
                    let _ = serve(stream, peer, id, &controller, &stop);
                    let mut controller = lock(&controller);
                    // A client gone: no more states to its port (which
                    // another client may take), and if it was moving the
                    // arm, the communication reflex stops it.
                    if controller
                        .client
                        .is_some_and(|(connection, _)| connection == id)
                    {
                        controller.client = None;
                    }
                    if controller
                        .motion
                        .as_ref()
                        .is_some_and(|m| m.connection == id)
                    {
                        controller.reflex(
                            FrankaError::CommunicationConstraintsViolation,
                            MoveStatus::Aborted,
                        );
                    }
                }));
            }
            Err(e) if nothing_arrived(&e) => std::thread::sleep(POLL),
            Err(_) => break,
        }
    }
    for connection in connections {
        let _ = connection.join();
    }
}

/// Reads exactly `buffer.len()` bytes; `Ok(false)` if the peer closed the
/// connection or the emulator is stopping.
fn read_exact(stream: &mut TcpStream, buffer: &mut [u8], stop: &AtomicBool) -> io::Result<bool> {
    let mut filled = 0;
    while filled < buffer.len() {
        if stop.load(Ordering::Relaxed) {
            return Ok(false);
        }
        match stream.read(&mut buffer[filled..]) {
            Ok(0) => return Ok(false),
            Ok(n) => filled += n,
            Err(e) if nothing_arrived(&e) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(true)
}

fn wire_error(error: bincode::Error) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, error)
}

/// Sends a response: the header (command, id, total size), then `status`.
fn respond(
    writer: &Writer,
    command: Command,
    command_id: u32,
    status: impl Serialize,
) -> io::Result<()> {
    let body = bincode::serialize(&status).map_err(wire_error)?;
    let size = (HEADER_BYTES + body.len()) as u32;
    let mut frame = bincode::serialize(&(command, command_id, size)).map_err(wire_error)?;
    frame.extend_from_slice(&body);
    let mut stream = writer
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    stream.write_all(&frame)
}

/// Serves one command connection until the client closes it.
fn serve(
    mut stream: TcpStream,
    peer: SocketAddr,
    connection: u32,
    controller: &Mutex<Controller>,
    stop: &AtomicBool,
) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(POLL))?;
    let writer: Writer = Arc::new(Mutex::new(stream.try_clone()?));
    loop {
        let mut header = [0_u8; HEADER_BYTES];
        if !read_exact(&mut stream, &mut header, stop)? {
            return Ok(());
        }
        let (command, command_id, size): (Command, u32, u32) =
            bincode::deserialize(&header).map_err(wire_error)?;
        let mut data = vec![0_u8; (size as usize).saturating_sub(HEADER_BYTES)];
        if !read_exact(&mut stream, &mut data, stop)? {
            return Ok(());
        }
        let mut controller = lock(controller);
        match command {
            Command::Connect => {
                let (version, udp_port): (u16, u16) =
                    bincode::deserialize(&data).map_err(wire_error)?;
                if version == FRANKA_ROBOT_VERSION {
                    controller.client = Some((connection, SocketAddr::new(peer.ip(), udp_port)));
                    controller.report.handshakes += 1;
                    respond(
                        &writer,
                        command,
                        command_id,
                        (ConnectStatusEnum::Success, FRANKA_ROBOT_VERSION),
                    )?;
                } else {
                    respond(
                        &writer,
                        command,
                        command_id,
                        (
                            ConnectStatusEnum::IncompatibleLibraryVersion,
                            FRANKA_ROBOT_VERSION,
                        ),
                    )?;
                }
            }
            Command::Move => {
                let (controller_mode, generator_mode): (u32, u32) =
                    bincode::deserialize(&data).map_err(wire_error)?;
                let status = if controller.in_error() || controller.motion.is_some() {
                    MoveStatus::CommandNotPossibleRejected
                } else if generator_mode != MOVE_CARTESIAN_POSITION {
                    // Only Cartesian pose motions are emulated.
                    MoveStatus::InvalidArgumentRejected
                } else {
                    controller.controller_mode = match controller_mode {
                        MOVE_CARTESIAN_IMPEDANCE => ControllerMode::CartesianImpedance,
                        MOVE_EXTERNAL_CONTROLLER => ControllerMode::ExternalController,
                        _ => ControllerMode::JointImpedance,
                    };
                    controller.motion = Some(Motion {
                        command_id,
                        reply_to: writer.clone(),
                        connection,
                        cycles: 0,
                    });
                    MoveStatus::MotionStarted
                };
                respond(&writer, command, command_id, status as u8)?;
            }
            Command::StopMove => {
                let status = if controller.in_error() {
                    StopMoveStatus::ReflexAborted as u8
                } else {
                    controller.end_motion(MoveStatus::Preempted);
                    StopMoveStatus::Success as u8
                };
                respond(&writer, command, command_id, status)?;
            }
            Command::AutomaticErrorRecovery => {
                controller.errors = [false; 41];
                controller.report.recoveries += 1;
                respond(
                    &writer,
                    command,
                    command_id,
                    GetterSetterStatus::Success as u8,
                )?;
            }
            Command::SetCollisionBehavior
            | Command::SetJointImpedance
            | Command::SetCartesianImpedance
            | Command::SetGuidingMode
            | Command::SetEEToK
            | Command::SetNEToEE
            | Command::SetLoad
            | Command::SetFilters => {
                respond(
                    &writer,
                    command,
                    command_id,
                    GetterSetterStatus::Success as u8,
                )?;
            }
            Command::GetCartesianLimit | Command::LoadModelLibrary | Command::GetRobotModel => {
                respond(
                    &writer,
                    command,
                    command_id,
                    GetterSetterStatus::CommandNotPossibleRejected as u8,
                )?;
            }
        }
    }
}

/// The 1 kHz loop: a state to the client every cycle and, during a motion,
/// the client's command for it.
fn stream_states(udp: &UdpSocket, controller: &Mutex<Controller>, stop: &AtomicBool) {
    let mut buffer = vec![0_u8; 4 * std::mem::size_of::<RobotCommand>()];
    while !stop.load(Ordering::Relaxed) {
        // The state is sent under the lock, so that once `set_silent`
        // returns no state is on its way.
        let (state, moving) = {
            let mut controller = lock(controller);
            match controller.client {
                Some((_, client)) if !controller.silent => {
                    controller.message_id += 1;
                    let state = controller.state();
                    if let Ok(datagram) = bincode::serialize(&state) {
                        // A client that has gone (its port closed) is not
                        // an error here.
                        let _ = udp.send_to(&datagram, client);
                    }
                    (state, controller.motion.is_some())
                }
                _ => {
                    drop(controller);
                    std::thread::sleep(Duration::from_secs_f64(CYCLE_S));
                    continue;
                }
            }
        };
        if !moving {
            std::thread::sleep(Duration::from_secs_f64(CYCLE_S));
            continue;
        }
        // Commands of earlier cycles (a finished motion's, repeated) are
        // skipped; a missing one counts as lost, as on the real network.
        let deadline = Instant::now() + COMMAND_WAIT;
        while Instant::now() < deadline {
            let Ok(size) = udp.recv(&mut buffer) else {
                break;
            };
            if let Ok(command) = bincode::deserialize::<RobotCommand>(&buffer[..size])
                && command.message_id == state.message_id
            {
                lock(controller).apply(&command);
                break;
            }
        }
    }
}
