//! The Panda driver (`franka_rust`) against the loopback emulator of the
//! controller's protocol: handshake, state stream, a short jerk-limited
//! move, a reflex and its recovery, silence, nobody listening; the cell
//! file's backend and the bring-up command. Each test serves on a loopback
//! address of its own (the protocol's port is fixed). Without the `panda`
//! feature, a cell file asking for the Panda is refused with how to build.

mod common;

/// The simulated cell with its arm swapped for `arm_backend`, in a temp file.
fn cell_with_arm(dir: &tempfile::TempDir, arm_backend: &str) -> std::path::PathBuf {
    common::sim_cell_copy(dir.path(), |text| {
        let start = text.find("[arm.backend.sim]").expect("sim arm table");
        let end = start + text[start..].find("\n\n").expect("end of the table");
        format!("{}{arm_backend}{}", &text[..start], &text[end..])
    })
}

const PANDA_BACKEND: &str = r#"[arm.backend.panda]
address = "ADDRESS"
dynamics_fraction = 0.1
ee_from_tcp = { translation_mm = [0.0, 0.0, 100.0], rotation_rpy_rad = [0.0, 0.0, 0.7853981633974483] }"#;

#[cfg(not(feature = "panda"))]
#[test]
fn without_the_feature_a_panda_cell_says_how_to_build() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = cell_with_arm(&dir, &PANDA_BACKEND.replace("ADDRESS", "172.16.0.2"));
    let error = cablecell::cell::load_cell(&path)
        .expect_err("refused")
        .to_string();
    assert!(error.contains("--features panda"), "{error}");
    assert!(error.contains("arm.backend"), "{error}");
}

#[cfg(not(feature = "panda"))]
#[test]
fn without_the_feature_the_bring_up_command_says_how_to_build() {
    let out = common::command()
        .args(["device", "arm", "--address", "172.16.0.2", "state"])
        .output()
        .expect("cablecell runs");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--features panda"), "{err}");
}

#[cfg(feature = "panda")]
mod emulated {
    use std::net::{IpAddr, Ipv4Addr};
    use std::sync::{Mutex, MutexGuard};

    use approx::assert_relative_eq;
    use cablecell::cell::CellDevices;
    use cablecell::hw::DeviceError;
    use cablecell::hw::arm::panda::panda_limits;
    use cablecell::hw::arm::panda_emulator::PandaEmulator;
    use cablecell::hw::arm::{Arm, Panda};
    use cablecell::sim::motion::move_duration_s;
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

    use super::*;

    /// franka_rust's client takes UDP port 61337 when it is free and
    /// accepts states from any sender: clients of tests running side by
    /// side could take each other's streams. So the tests take turns.
    static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

    fn one_at_a_time() -> MutexGuard<'static, ()> {
        ONE_AT_A_TIME
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn ip(last: u8) -> IpAddr {
        IpAddr::V4(Ipv4Addr::new(127, 0, 0, last))
    }

    /// The end effector where the emulated arm starts: 0.5 m out, 0.4 m up,
    /// pointing down, 166° from the base's orientation. Not exactly 180°:
    /// there franka_rust's Cartesian rate limiter (nalgebra's
    /// `UnitQuaternion::from_matrix`, iterating from the identity) returns
    /// a wrong orientation, which a real controller's measured poses never
    /// hit exactly.
    fn start_pose() -> Isometry3<f64> {
        Isometry3::new(
            Vector3::new(500.0, 20.0, 400.0),
            Vector3::new(2.9, 0.2, 0.1),
        )
    }

    /// The TCP 100 mm beyond the flange's end effector, turned 45° about z.
    fn ee_from_tcp() -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 100.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_4),
        )
    }

    const FRACTION: f64 = 0.1;

    fn panda(last: u8) -> Panda {
        Panda::new(
            &format!("127.0.0.{last}"),
            ee_from_tcp(),
            panda_limits(FRACTION),
        )
    }

    #[test]
    fn connects_and_reads_the_tcp_pose_in_the_base_frame_in_mm() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(2), start_pose()).expect("emulator");
        let mut arm = panda(2);
        let pose = arm.base_from_tcp().expect("state");
        assert_relative_eq!(pose, start_pose() * ee_from_tcp(), epsilon = 1e-9);
        // The TCP is 100 mm beyond the end effector.
        let ee_to_tcp_mm = pose.translation.vector - start_pose().translation.vector;
        assert_relative_eq!(ee_to_tcp_mm.norm(), 100.0, epsilon = 1e-9);
        // A second read uses the same connection.
        arm.base_from_tcp().expect("state again");
        assert_eq!(emulator.report().handshakes, 1);
    }

    #[test]
    fn a_short_move_is_a_jerk_limited_straight_line_that_arrives() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(3), start_pose()).expect("emulator");
        let mut arm = panda(3);
        let from = arm.base_from_tcp().expect("state");
        let offset = Vector3::new(30.0, -10.0, -20.0);
        let target = Translation3::from(offset) * from;
        let speed_mm_s = 20.0;
        arm.move_linear(&target, speed_mm_s).expect("move");

        assert_relative_eq!(arm.base_from_tcp().expect("state"), target, epsilon = 1e-6);
        assert_relative_eq!(
            emulator.base_from_ee() * ee_from_tcp(),
            target,
            epsilon = 1e-6
        );
        let report = emulator.report();
        assert_eq!((report.motions_finished, report.motions_aborted), (1, 0));
        // The commanded speed cruises at the cap and never exceeds it.
        assert!(report.peak_speed_mm_s <= speed_mm_s + 1e-6, "{report:?}");
        assert!(report.peak_speed_mm_s > 0.95 * speed_mm_s, "{report:?}");
        // One command per 1 ms cycle of the controller's clock, for the
        // profile's duration.
        let duration_s = move_duration_s(offset.norm(), 0.0, speed_mm_s, &panda_limits(FRACTION))
            .expect("profile");
        let cycles = report.commanded_cycles as f64;
        assert!(
            (cycles - duration_s * 1000.0).abs() <= 2.0,
            "{report:?}, {duration_s} s"
        );

        // Turning about the base's z while moving: the TCP arrives too.
        let turned = Isometry3::from_parts(
            Translation3::from(target.translation.vector + Vector3::new(0.0, 5.0, 0.0)),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.1) * target.rotation,
        );
        arm.move_linear(&turned, speed_mm_s).expect("turn");
        assert_relative_eq!(arm.base_from_tcp().expect("state"), turned, epsilon = 1e-6);
        assert_eq!(emulator.report().motions_finished, 2);
    }

    #[test]
    fn a_reflex_aborts_the_move_and_recovery_clears_it() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(4), start_pose()).expect("emulator");
        let mut arm = panda(4);
        let from = arm.base_from_tcp().expect("state");
        let target = Translation3::new(0.0, 40.0, 0.0) * from;
        emulator.reflex_during_next_motion(200);

        let error = arm
            .move_linear(&target, 20.0)
            .expect_err("the reflex aborts it");
        let DeviceError::Refused { reason, .. } = &error else {
            panic!("expected a refusal, got {error:?}");
        };
        assert!(
            reason.to_lowercase().contains("cartesian reflex"),
            "{reason}"
        );
        assert!(reason.contains("recover"), "{reason}");
        assert!(emulator.has_errors());
        // The arm stopped part of the way.
        let stopped = emulator.base_from_ee() * ee_from_tcp();
        let travelled_mm = (stopped.translation.vector - from.translation.vector).norm();
        assert!(travelled_mm > 0.0 && travelled_mm < 40.0, "{travelled_mm}");

        // While in reflex the state is refused, and stopping is a no-op.
        assert!(matches!(
            arm.base_from_tcp(),
            Err(DeviceError::Refused { .. })
        ));
        arm.stop().expect("a reflex has already stopped the arm");

        arm.recover().expect("recovery");
        assert!(!emulator.has_errors());
        assert_eq!(emulator.report().recoveries, 1);
        arm.move_linear(&target, 20.0).expect("moves again");
        assert_relative_eq!(arm.base_from_tcp().expect("state"), target, epsilon = 1e-6);
        let report = emulator.report();
        assert_eq!((report.motions_finished, report.motions_aborted), (1, 1));
    }

    #[test]
    fn a_silent_controller_is_a_timeout_and_the_next_call_reconnects() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(5), start_pose()).expect("emulator");
        let mut arm = panda(5);
        arm.base_from_tcp().expect("state");
        emulator.set_silent(true);
        // States sent between the first read and the silence wait in the
        // socket, and one read takes them all; the read after it waits in
        // vain.
        let mut read = arm.base_from_tcp();
        if read.is_ok() {
            read = arm.base_from_tcp();
        }
        assert!(matches!(read, Err(DeviceError::Timeout { .. })), "{read:?}");
        emulator.set_silent(false);
        arm.base_from_tcp().expect("state after the link came back");
        assert_eq!(emulator.report().handshakes, 2);
    }

    #[test]
    fn nobody_listening_is_a_clear_error() {
        let _turn = one_at_a_time();
        let mut arm = panda(6);
        let error = arm.base_from_tcp().expect_err("no controller");
        let DeviceError::Disconnected { port, reason, .. } = &error else {
            panic!("expected a lost link, got {error:?}");
        };
        assert_eq!(port, "127.0.0.6:1337");
        assert!(reason.contains("cannot connect"), "{reason}");
        assert!(matches!(
            arm.move_linear(&Isometry3::identity(), 10.0),
            Err(DeviceError::Disconnected { .. })
        ));
    }

    #[test]
    fn too_fast_a_move_is_refused_before_anything_is_sent() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(7), start_pose()).expect("emulator");
        let dir = tempfile::tempdir().expect("tempdir");
        let path = cell_with_arm(&dir, &PANDA_BACKEND.replace("ADDRESS", "127.0.0.7"));
        let file = cablecell::cell::load_cell(&path).expect("cell file");
        let mut cell = CellDevices::build(&file, 1).expect("the cell builds");
        let error = cell
            .arm
            .move_linear(&start_pose(), file.arm.max_speed_mm_s * 2.0)
            .expect_err("too fast");
        assert!(matches!(error, DeviceError::TooFast { .. }), "{error:?}");
        assert_eq!(emulator.report().handshakes, 0);
    }

    #[test]
    fn a_cell_file_with_the_panda_backend_drives_it() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(8), start_pose()).expect("emulator");
        let dir = tempfile::tempdir().expect("tempdir");
        let path = cell_with_arm(&dir, &PANDA_BACKEND.replace("ADDRESS", "127.0.0.8"));
        let file = cablecell::cell::load_cell(&path).expect("cell file");
        let mut cell = CellDevices::build(&file, 1).expect("the cell builds");
        let pose = cell.arm.base_from_tcp().expect("state");
        assert_relative_eq!(pose, start_pose() * ee_from_tcp(), epsilon = 1e-9);
        let target = Translation3::new(5.0, 0.0, 0.0) * pose;
        cell.arm.move_linear(&target, 10.0).expect("move");
        assert_relative_eq!(
            emulator.base_from_ee() * ee_from_tcp(),
            target,
            epsilon = 1e-6
        );
    }

    #[test]
    fn a_bad_panda_address_in_a_cell_file_is_refused_at_its_line() {
        let _turn = one_at_a_time();
        let dir = tempfile::tempdir().expect("tempdir");
        let path = cell_with_arm(&dir, &PANDA_BACKEND.replace("ADDRESS", "10.0.0.2:1337"));
        let error = cablecell::cell::load_cell(&path)
            .expect_err("refused")
            .to_string();
        assert!(error.contains("arm.backend.panda.address"), "{error}");
        assert!(error.contains("without a port"), "{error}");
    }

    /// `cablecell device arm --address 127.0.0.LAST ARGS...`: its exit
    /// status, standard output and standard error.
    fn device_arm(last: u8, args: &[&str]) -> (Option<i32>, String, String) {
        let out = common::command()
            .args(["device", "arm", "--address", &format!("127.0.0.{last}")])
            .args(args)
            .output()
            .expect("cablecell runs");
        let text = |bytes: &[u8]| String::from_utf8_lossy(bytes).into_owned();
        (out.status.code(), text(&out.stdout), text(&out.stderr))
    }

    #[test]
    fn the_bring_up_command_reads_the_state_and_makes_a_guarded_move() {
        let _turn = one_at_a_time();
        let emulator = PandaEmulator::start(ip(9), start_pose()).expect("emulator");
        let (status, out, err) = device_arm(9, &["state"]);
        assert_eq!(status, Some(0), "{err}");
        // Without a cell file the TCP is the end effector set in Desk.
        assert!(out.contains("x +500.000 y +20.000 z +400.000 mm"), "{out}");

        let (status, out, err) = device_arm(9, &["move-rel", "10", "0", "-5"]);
        assert_eq!(status, Some(0), "{err}");
        assert!(out.contains("x +510.000 y +20.000 z +395.000 mm"), "{out}");
        assert_relative_eq!(
            emulator.base_from_ee().translation.vector,
            Vector3::new(510.0, 20.0, 395.0),
            epsilon = 1e-6
        );

        // Too far, or too fast: refused before the arm moves.
        let (status, _, err) = device_arm(9, &["move-rel", "60", "0", "0"]);
        assert_eq!(status, Some(2), "{err}");
        assert!(err.contains("at most 50 mm"), "{err}");
        let (status, _, err) = device_arm(9, &["move-rel", "1", "0", "0", "--speed", "50"]);
        assert_eq!(status, Some(2), "{err}");
        assert!(
            err.contains("refused move_linear at 50 mm/s: the cell allows (0, 20] mm/s"),
            "{err}"
        );
        assert_eq!(emulator.report().motions_finished, 1);
    }

    #[test]
    fn the_bring_up_command_says_when_nobody_answers() {
        let _turn = one_at_a_time();
        let (status, _, err) = device_arm(10, &["state"]);
        assert_eq!(status, Some(3));
        assert!(
            err.contains("127.0.0.10:1337") && err.contains("cannot connect"),
            "{err}"
        );
    }
}
