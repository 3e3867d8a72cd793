//! Recordings: what a run writes, read back with the mcap crate; a file
//! cut short; `cablecell replay`; a campaign's per-trial recordings.

use std::collections::BTreeMap;
use std::path::Path;

mod common;

use common::root;

use cablecell::campaign::run::{Campaign, Overrides};
use cablecell::orchestrator::Runner;
use cablecell::perception::tactile::Estimator;
use cablecell::record::RunRecord;
use cablecell::recording::replay::Replay;
use cablecell::recording::{Recording, Topic};
use cablecell::task::load_task;

/// Runs the regrasp task with `seed`, recorded to `path`.
fn recorded_run(path: &Path, seed: u64) -> RunRecord {
    let task = load_task(&root().join("tasks/regrasp.toml")).unwrap();
    let cell = common::sim_cell_with_oracle();
    let mut runner = Runner::for_task(&task, &cell, seed).expect("a simulated cell builds");
    runner.record_to(path, true).unwrap();
    runner.run_to_end().unwrap();
    assert_eq!(runner.finish_recording().unwrap().as_deref(), Some(path));
    runner.into_record()
}

/// What the run record says each channel must hold; `/tf` (a message a
/// step) is checked apart. Channels with no message are not in the file.
fn expected_counts(record: &RunRecord) -> BTreeMap<&'static str, u64> {
    let (bias_frames, average_frames) = (50, 10); // tasks/regrasp.toml
    let frames = (bias_frames + average_frames * record.grasps.len()) as u64;
    let dv_frames = frames - bias_frames as u64;
    let transitions = record.transitions.len() as u64;
    let grasps = record.grasps.len() as u64;
    // One target per approach, trial grasp and regrasp.
    let targets = 2 + (grasps - 1);
    BTreeMap::from([
        ("/run", 1),
        ("/state", transitions),
        ("/log", transitions + 1),
        ("/tactile/raw", frames),
        ("/tactile/dv", dv_frames),
        ("/tactile/fit", grasps),
        ("/tactile/wire_params", grasps),
        ("/tactile/image", dv_frames),
        ("/arm/grasp_pose", grasps),
        ("/arm/target", targets),
        ("/cable/shapes", grasps),
        // The pad at each Δv frame, the shapes at each grasp, the
        // detected cable once. The oracle detector looks at no image: no
        // camera channel.
        ("/scene", dv_frames + grasps + 1),
    ])
}

#[test]
fn a_recording_holds_every_channel_with_foxglove_schemas_and_the_right_counts() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let record = recorded_run(&path, 3);
    assert!(record.grasps.len() >= 2, "seed 3 regrasps once");
    let bytes = std::fs::read(&path).unwrap();

    // The summary, as any MCAP reader (Foxglove) sees it.
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let stats = summary.stats.expect("statistics");
    let mut counts = BTreeMap::new();
    for (id, channel) in &summary.channels {
        let schema = channel.schema.as_ref().expect("a schema");
        let (expected_schema, encoding) = match channel.topic.as_str() {
            "/log" => ("foxglove.Log", "json"),
            "/arm/grasp_pose" | "/arm/target" => ("foxglove.PoseInFrame", "json"),
            "/tf" => ("foxglove.FrameTransforms", "protobuf"),
            "/scene" => ("foxglove.SceneUpdate", "protobuf"),
            "/tactile/image" => ("foxglove.RawImage", "protobuf"),
            _ => ("cablecell.", "json"),
        };
        assert!(schema.name.starts_with(expected_schema), "{}", schema.name);
        assert_eq!(channel.message_encoding, encoding, "{}", channel.topic);
        let schema_encoding = if encoding == "json" {
            "jsonschema"
        } else {
            "protobuf"
        };
        assert_eq!(schema.encoding, schema_encoding, "{}", channel.topic);
        counts.insert(
            channel.topic.as_str(),
            stats.channel_message_counts.get(id).copied().unwrap_or(0),
        );
    }
    let tf = counts.remove("/tf").expect("a /tf channel");
    assert!(tf > record.transitions.len() as u64 / 2, "{tf}");
    assert_eq!(counts, expected_counts(&record));

    // Chunked, compressed and indexed, for Foxglove to seek in.
    assert!(!summary.chunk_indexes.is_empty());
    assert!(
        summary
            .chunk_indexes
            .iter()
            .all(|c| c.compression == "zstd" && !c.message_index_offsets.is_empty())
    );
    // The metadata record names the program and the run.
    let metadata = mcap::read::LinearReader::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .find_map(|record| match record {
            mcap::records::Record::Metadata(m) => Some(m),
            _ => None,
        })
        .expect("a metadata record");
    assert_eq!(metadata.name, "cablecell");
    assert_eq!(metadata.metadata["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(metadata.metadata["task"], record.task);
    assert_eq!(metadata.metadata["seed"], "3");

    // Every JSON message has a Foxglove timestamp on the wall clock (the
    // run is today, not 1970), equal to its log time; log times are in
    // order.
    let mut last_ns = 0;
    let this_year_ns = 1_700_000_000 * 1_000_000_000;
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        assert!(message.log_time >= last_ns, "{}", message.channel.topic);
        assert!(message.log_time > this_year_ns, "{}", message.log_time);
        last_ns = message.log_time;
        if message.channel.message_encoding == "json" {
            let value: serde_json::Value = serde_json::from_slice(&message.data).unwrap();
            let stamp = &value["timestamp"];
            let ns =
                stamp["sec"].as_u64().unwrap() * 1_000_000_000 + stamp["nsec"].as_u64().unwrap();
            assert_eq!(ns, message.log_time, "{}", message.channel.topic);
        }
    }
    let states: Vec<serde_json::Value> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/state")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    let recorded: Vec<&str> = states.iter().map(|s| s["to"].as_str().unwrap()).collect();
    let expected: Vec<&str> = record.transitions.iter().map(|t| t.to).collect();
    assert_eq!(recorded, expected);

    // The paper's wire parameters are the centroid fit's.
    let wire: Vec<cablecell::recording::schema::WireParamsMessage> = Recording::read(&path)
        .unwrap()
        .decode(Topic::WireParams)
        .unwrap();
    assert_eq!(wire.len(), record.grasps.len());
    for (params, grasp) in wire.iter().zip(&record.grasps) {
        let Some(cablecell::perception::tactile::Estimate::Centroids(fit)) = &grasp.fit else {
            panic!("the regrasp task's estimator is the centroids'");
        };
        assert_eq!(
            params.direction.as_deref(),
            Some(fit.direction.to_string().as_str())
        );
        assert_eq!((params.m, params.n_mm), (fit.slope_m, fit.intercept_n_mm));
        assert_eq!(params.a_per_mm, fit.quadratic.map(|q| q.a));
        assert_eq!((params.h_v, params.v_v), (Some(fit.h_v), Some(fit.v_v)));
    }
}

#[test]
fn a_truncated_recording_is_reported_and_what_it_holds_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    recorded_run(&path, 3);
    let whole = Recording::read(&path).unwrap();
    assert_eq!(whole.truncated, None);
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.mcap");
    // Cut in the middle of a message.
    std::fs::write(&cut, &bytes[..bytes.len() / 2 + 7]).unwrap();
    let part = Recording::read(&cut).unwrap();
    assert!(part.truncated.is_some());
    assert!(!part.messages.is_empty() && part.messages.len() < whole.messages.len());
    for (a, b) in part.messages.iter().zip(&whole.messages) {
        assert_eq!(
            (&a.topic, a.log_time_ns, &a.data),
            (&b.topic, b.log_time_ns, &b.data)
        );
    }
    // The timeline up to the cut is still there.
    let replay = Replay::of(&part).unwrap();
    assert!(!replay.transitions.is_empty());

    let output = common::cablecell(&["replay", cut.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}");
    assert!(stdout.starts_with("truncated recording ("), "{stdout}");
    assert!(stdout.contains("idle → prepare"), "{stdout}");
}

#[test]
fn replay_fits_the_recorded_frames_again() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let record = recorded_run(&path, 3);
    let replay = Replay::of(&Recording::read(&path).unwrap()).unwrap();
    assert_eq!(replay.run.seed, 3);
    assert_eq!(replay.run.estimator, Estimator::Centroids);
    // The recorded estimator on the recorded frames gives the run's answers.
    let again = replay.refit(Estimator::Centroids);
    assert_eq!(again.len(), record.grasps.len());
    for (refit, grasp) in again.iter().zip(&record.grasps) {
        assert_eq!(refit.frames, 10);
        let line = refit.line.as_ref().unwrap();
        let expected = grasp.fit.as_ref().unwrap().line();
        assert!((line.n_mm - expected.n_mm).abs() < 1e-9);
        assert!((line.alpha_rad - expected.alpha_rad).abs() < 1e-9);
        assert_eq!(refit.truth, grasp.truth.as_ref().map(|t| t.line));
    }
    // Another estimator on the same frames answers differently.
    let ridge = replay.refit(Estimator::Ridge);
    assert_eq!(ridge.len(), again.len());
    let moved = (ridge[0].line.as_ref().unwrap().n_mm - again[0].line.as_ref().unwrap().n_mm).abs();
    assert!(moved > 1e-6, "ridge gave the centroids' answer");

    let output = common::cablecell(&["replay", path.to_str().unwrap(), "--estimator", "ridge"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}");
    assert!(stdout.contains("/tactile/raw 70"), "{stdout}");
    assert!(
        stdout.contains("ridge again on the recorded frames (2 grasps)"),
        "{stdout}"
    );
}

#[test]
fn replay_refuses_what_is_not_a_recording() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("not.mcap");
    std::fs::write(&path, "not an mcap file at all").unwrap();
    let output = common::cablecell(&["replay", path.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("not.mcap"), "{stderr}");
}

#[test]
fn the_run_command_records_where_it_is_told() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("deep/run.mcap");
    let output = common::cablecell(&[
        "run",
        "tasks/regrasp.toml",
        "--cell",
        common::sim_cell_with_oracle_file(dir.path())
            .to_str()
            .unwrap(),
        "--seed",
        "3",
        "--record",
        path.to_str().unwrap(),
    ]);
    assert!(output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("recorded to"), "{stderr}");
    let recording = Recording::read(&path).unwrap();
    assert_eq!(recording.truncated, None);
    assert_eq!(recording.count(Topic::TactileFit), 2);
}

#[test]
fn every_campaign_trial_is_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let overrides = Overrides {
        trials: Some(3),
        seed: Some(5),
        out: Some(dir.path().to_owned()),
        no_record: false,
        shard: None,
    };
    let campaign =
        Campaign::load(&root().join("tasks/paper-regrasp-campaign.toml"), overrides).unwrap();
    let entries = campaign.run(false, 2, |_| {}).unwrap();
    assert_eq!(entries.len(), 3 * campaign.file.policies.len());
    for entry in &entries {
        let name = entry.recording.as_ref().expect("recorded");
        let recording = Recording::read(&campaign.recordings_folder().join(name)).unwrap();
        assert_eq!(recording.truncated, None);
        let replay = Replay::of(&recording).unwrap();
        assert_eq!(replay.run.seed, entry.seed);
        assert_eq!(replay.fits.len(), entry.grasps.len());
        // The metadata record says which trial it is.
        let bytes = std::fs::read(campaign.recordings_folder().join(name)).unwrap();
        let metadata = mcap::read::LinearReader::new(&bytes)
            .unwrap()
            .map(Result::unwrap)
            .find_map(|record| match record {
                mcap::records::Record::Metadata(m) => Some(m.metadata),
                _ => None,
            })
            .expect("a metadata record");
        assert_eq!(metadata["policy"], entry.policy);
        assert_eq!(metadata["trial"], entry.trial.to_string());
        assert_eq!(metadata["seed"], entry.seed.to_string());
        let offset: f64 = metadata["perturbation.start_offset_mm"].parse().unwrap();
        assert_eq!(offset, entry.perturbation.start_offset_mm);
        // The oracle detector takes no image: no empty camera channel.
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        assert!(
            summary
                .channels
                .values()
                .all(|c| !c.topic.starts_with("/camera"))
        );
    }
}

#[test]
fn a_plan_changed_mid_run_is_recorded_with_the_grasps_it_judged() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let mut task = load_task(&root().join("tasks/regrasp.toml")).unwrap();
    let cell = common::sim_cell_with_oracle();
    let mut runner = Runner::for_task(&task, &cell, 3).expect("a simulated cell builds");
    runner.record_to(&path, true).unwrap();
    while runner.record().grasps.is_empty() {
        assert!(runner.step().unwrap());
    }
    task.tactile.estimator = Estimator::Ridge;
    runner
        .set_plan(cablecell::orchestrator::Plan::new(&task, &cell))
        .unwrap();
    runner.run_to_end().unwrap();
    runner.finish_recording().unwrap();
    let record = runner.into_record();
    assert!(record.grasps.len() >= 2);

    let replay = Replay::of(&Recording::read(&path).unwrap()).unwrap();
    assert_eq!(replay.run.estimator, Estimator::Centroids);
    assert_eq!(replay.changes.len(), 1);
    assert_eq!(replay.changes[0].estimator, Estimator::Ridge);
    let estimators: Vec<Estimator> = replay.fits.iter().map(|f| f.estimator).collect();
    assert_eq!(estimators[0], Estimator::Centroids);
    assert!(estimators[1..].iter().all(|e| *e == Estimator::Ridge));
}

#[test]
fn a_vision_run_records_its_camera_image_and_replay_detects_again() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("vision.mcap");
    let run = common::json_of(&[
        "run",
        "tasks/regrasp.toml",
        "--seed",
        "2",
        "--json",
        "--record",
        path.to_str().unwrap(),
    ]);
    let recording = Recording::read(&path).unwrap();
    assert_eq!(recording.count(Topic::CameraImage), 1);
    let images: Vec<cablecell::recording::schema::CompressedImageMessage> =
        recording.decode(Topic::CameraImage).unwrap();
    assert_eq!(images[0].format, "png");
    assert!(images[0].data.starts_with(b"\x89PNG"));

    // The command line's settings see the whole image.
    let output = common::cablecell(&[
        "replay",
        path.to_str().unwrap(),
        "--vision",
        "--mask",
        "network",
    ]);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{text}");
    assert!(
        text.contains("vision again on the recorded images (1), with the options given:"),
        "{text}"
    );
    assert!(text.contains("start-up: "), "{text}");
    assert!(text.contains("Network mask"), "{text}");
    assert!(text.contains("cable 0: grasp at ("), "{text}");
    let cable_line = text
        .lines()
        .find(|line| line.contains("cable 0: grasp at ("))
        .expect("a cable's line");
    assert!(cable_line.contains(", confidence "), "{text}");

    // The cell's own settings (its region of interest, network scale and
    // straight edges kept) see what the task's detect state saw: its one
    // cable, not the finger's marker as a second.
    let detected = run["detected"].as_array().expect("the run's detections");
    assert_eq!(detected.len(), 1, "{run}");
    let output = common::cablecell(&[
        "replay",
        path.to_str().unwrap(),
        "--vision",
        "--cell",
        "config/cell.sim.toml",
    ]);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{text}");
    assert!(text.contains("config/cell.sim.toml's detector"), "{text}");
    assert!(text.contains(" 1 cable(s), Network mask"), "{text}");

    let image = dir.path().join("camera.png");
    std::fs::write(&image, &images[0].data).unwrap();
    // `detect --json` on the recorded image with the cell file `cell`.
    let detect_with = |cell: &str, options: &[&str]| {
        let mut args = vec!["detect", image.to_str().unwrap(), "--cell", cell, "--json"];
        args.extend_from_slice(options);
        common::json_of(&args)
    };
    let report = detect_with("config/cell.sim.toml", &[]);
    let found = &report["images"][0];
    assert_eq!(found["cables"].as_array().unwrap().len(), 1, "{report}");
    let confidence = found["cables"][0]["confidence"].as_f64().unwrap();
    assert!(
        (confidence - detected[0]["confidence"].as_f64().unwrap()).abs() < 1e-9,
        "{report}"
    );
    let at = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let by_detect = at(&found["grasp_frames_in_base"][0]["translation_mm"]);
    let by_task = at(&detected[0]["base_from_cable"]["translation_mm"]);
    for (a, b) in by_detect.iter().zip(&by_task) {
        assert!((a - b).abs() < 1e-6, "{by_detect:?} against {by_task:?}");
    }

    // The cell's confidence floor is the cell's too: above the cable's
    // confidence, `detect --cell` drops it, whatever the command line says.
    let cell = std::fs::read_to_string(common::root().join("config/cell.sim.toml")).unwrap();
    let floor = (confidence + 1.0) / 2.0;
    let strict = cell.replacen(
        "straight_edge_radius_px = 0.0",
        &format!("straight_edge_radius_px = 0.0\nmin_confidence = {floor}"),
        1,
    );
    assert_ne!(
        strict, cell,
        "the shipped cell sets straight_edge_radius_px"
    );
    let model = common::root().join("models/cable_segmentation.onnx");
    let strict = strict.replacen(
        "\"../models/cable_segmentation.onnx\"",
        &format!("{:?}", model.to_str().unwrap()),
        1,
    );
    let strict_cell = dir.path().join("strict.toml");
    std::fs::write(&strict_cell, strict).unwrap();
    let report = detect_with(strict_cell.to_str().unwrap(), &["--min-confidence", "0"]);
    let found = &report["images"][0];
    assert_eq!(found["cables"].as_array().unwrap().len(), 0, "{report}");
}
