//! What Foxglove gets: every channel of a recording holds messages of the
//! schema it names (Foxglove's protobuf ones decoded with the `foxglove`
//! crate's types, the JSON ones checked field by field against their JSON
//! schema), and `cablecell run --live` serves the same channels over
//! Foxglove's WebSocket protocol to a real client.

use std::collections::BTreeMap;
use std::io::ErrorKind;
use std::net::{TcpListener, TcpStream};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::root;

use cablecell::cell::load_cell;
use cablecell::orchestrator::Runner;
use cablecell::task::load_task;
use foxglove::Decode;
use foxglove::messages::{
    CameraCalibration, FrameTransforms, ImageAnnotations, RawImage, SceneUpdate,
};
use serde_json::Value;

/// The regrasp task with seed 2 on the shipped cell (the vision detector,
/// so the camera channels are there too), recorded; its messages by topic.
fn vision_run_messages(dir: &std::path::Path) -> (mcap::Summary, BTreeMap<String, Vec<Vec<u8>>>) {
    let path = dir.join("vision.mcap");
    let task = load_task(&root().join("tasks/regrasp.toml")).unwrap();
    let cell = load_cell(&root().join("config/cell.sim.toml")).unwrap();
    let mut runner = Runner::for_task(&task, &cell, 2).expect("a simulated cell builds");
    runner.record_to(&path, true).unwrap();
    runner.run_to_end().unwrap();
    runner.finish_recording().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let mut messages: BTreeMap<String, Vec<Vec<u8>>> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        messages
            .entry(message.channel.topic.clone())
            .or_default()
            .push(message.data.into_owned());
    }
    (summary, messages)
}

/// `value` against a JSON schema as cablecell writes them: every property
/// the schema lists is there, with one of its types, recursively.
fn conforms(value: &Value, schema: &Value, at: &str) {
    let types: Vec<&str> = match &schema["type"] {
        Value::String(t) => vec![t.as_str()],
        Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
        _ => return,
    };
    let ok = types.iter().any(|t| match *t {
        "object" => value.is_object(),
        "array" => value.is_array(),
        "string" => value.is_string(),
        "integer" => value.is_i64() || value.is_u64(),
        "number" => value.is_number(),
        "null" => value.is_null(),
        _ => false,
    });
    assert!(ok, "{at}: {value} is not {types:?}");
    if let (Value::Object(fields), Some(properties)) = (value, schema["properties"].as_object()) {
        for (name, property) in properties {
            let field = fields
                .get(name)
                .unwrap_or_else(|| panic!("{at}: no field {name}"));
            conforms(field, property, &format!("{at}.{name}"));
        }
    }
    if let (Value::Array(items), Some(item)) = (value, schema.get("items")) {
        for (i, value) in items.iter().enumerate() {
            conforms(value, item, &format!("{at}[{i}]"));
        }
    }
}

/// Foxglove's required fields of its JSON-encoded schemas, with their
/// JSON types (from Foxglove's schema reference).
fn foxglove_json_fields(schema: &str) -> &'static [(&'static str, &'static str)] {
    match schema {
        "foxglove.Log" => &[
            ("timestamp", "object"),
            ("level", "integer"),
            ("message", "string"),
            ("name", "string"),
            ("file", "string"),
            ("line", "integer"),
        ],
        "foxglove.PoseInFrame" => &[
            ("timestamp", "object"),
            ("frame_id", "string"),
            ("pose", "object"),
        ],
        "foxglove.CompressedImage" => &[
            ("timestamp", "object"),
            ("frame_id", "string"),
            ("data", "string"),
            ("format", "string"),
        ],
        other => panic!("{other}: not one of Foxglove's JSON schemas here"),
    }
}

#[test]
fn every_channel_holds_the_schema_it_names() {
    let dir = tempfile::tempdir().unwrap();
    let (summary, messages) = vision_run_messages(dir.path());
    let topics: Vec<&str> = summary
        .channels
        .values()
        .map(|c| c.topic.as_str())
        .collect();
    for topic in cablecell::recording::Topic::ALL {
        assert!(topics.contains(&topic.name()), "{} missing", topic.name());
    }
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().expect("a schema");
        let data = &messages[&channel.topic];
        assert!(!data.is_empty(), "{}", channel.topic);
        match schema.encoding.as_str() {
            "protobuf" => {
                assert_eq!(channel.message_encoding, "protobuf");
                for bytes in data {
                    check_protobuf(&schema.name, bytes);
                }
            }
            "jsonschema" => {
                assert_eq!(channel.message_encoding, "json");
                let json_schema: Value = serde_json::from_slice(&schema.data).unwrap();
                assert_eq!(json_schema["title"], schema.name.as_str());
                for bytes in data {
                    let value: Value = serde_json::from_slice(bytes).unwrap();
                    conforms(&value, &json_schema, &channel.topic);
                    if schema.name.starts_with("foxglove.") {
                        for (field, kind) in foxglove_json_fields(&schema.name) {
                            let mut wanted = serde_json::json!({ "type": *kind });
                            if *kind == "object" && *field == "timestamp" {
                                wanted = serde_json::json!({"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}});
                            }
                            conforms(
                                &value[*field],
                                &wanted,
                                &format!("{}.{field}", channel.topic),
                            );
                        }
                    }
                }
            }
            other => panic!("{}: schema encoding {other}", channel.topic),
        }
    }
}

/// Decodes one message with the `foxglove` crate's type of `schema` and
/// checks what Foxglove needs of it: frames and units, sizes.
fn check_protobuf(schema: &str, bytes: &[u8]) {
    match schema {
        "foxglove.FrameTransforms" => {
            let tf = FrameTransforms::decode(bytes).unwrap();
            let children: Vec<&str> = tf
                .transforms
                .iter()
                .map(|t| t.child_frame_id.as_str())
                .collect();
            for frame in ["sensor", "marker", "tcp", "camera"] {
                assert!(children.contains(&frame), "{children:?}");
            }
            for t in &tf.transforms {
                let p = t.translation.unwrap();
                // Metres: the cell is within a metre of the base.
                assert!(
                    p.x.abs() < 2.0 && p.y.abs() < 2.0 && p.z.abs() < 2.0,
                    "{t:?}"
                );
                let q = t.rotation.unwrap();
                let norm = (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w).sqrt();
                assert!((norm - 1.0).abs() < 1e-9, "{t:?}");
                assert!(t.timestamp.is_some());
            }
        }
        "foxglove.SceneUpdate" => {
            let scene = SceneUpdate::decode(bytes).unwrap();
            assert!(!scene.entities.is_empty());
            for entity in &scene.entities {
                match entity.id.as_str() {
                    "pad" => {
                        assert_eq!(
                            (entity.frame_id.as_str(), entity.spheres.len()),
                            ("sensor", 25)
                        );
                        assert!(entity.frame_locked);
                    }
                    id => {
                        assert!(id.starts_with("cable/"), "{id}");
                        assert_eq!(entity.frame_id, "base");
                        let line = &entity.lines[0];
                        assert!(line.points.len() >= 2, "{id}");
                        assert!(
                            line.points
                                .iter()
                                .all(|p| p.x.abs() < 2.0 && p.z.abs() < 2.0)
                        );
                    }
                }
            }
        }
        "foxglove.RawImage" => {
            let image = RawImage::decode(bytes).unwrap();
            assert_eq!(image.encoding, "rgb8");
            assert_eq!(image.data.len(), (image.step * image.height) as usize);
        }
        "foxglove.ImageAnnotations" => {
            let drawn = ImageAnnotations::decode(bytes).unwrap();
            assert!(!drawn.points.is_empty() && !drawn.texts.is_empty());
            // The detected cable lies in the 640×480 image.
            let line = &drawn.points[0];
            assert!(line.points.len() >= 2);
            assert!(
                line.points
                    .iter()
                    .all(|p| (0.0..640.0).contains(&p.x) && (0.0..480.0).contains(&p.y))
            );
        }
        "foxglove.CameraCalibration" => {
            let calibration = CameraCalibration::decode(bytes).unwrap();
            assert_eq!((calibration.width, calibration.height), (640, 480));
            assert_eq!((calibration.k.len(), calibration.p.len()), (9, 12));
            assert_eq!(calibration.frame_id, "camera");
        }
        other => panic!("{other}: no check for this schema"),
    }
}

/// A port nobody listens on now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// Kills the child when the test ends, however it ends.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn run_live_serves_foxglove_websocket_with_tactile_frames_and_transitions() {
    let dir = tempfile::tempdir().unwrap();
    let cell = common::sim_cell_with_oracle_file(dir.path());
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let report_path = dir.path().join("report.json");
    let child = common::command()
        .args([
            "run",
            "tasks/regrasp.toml",
            "--seed",
            "3",
            "--no-record",
            "--json",
        ])
        .args(["--cell", cell.to_str().unwrap(), "--live", &addr])
        .stdout(std::fs::File::create(&report_path).unwrap())
        .stderr(Stdio::null())
        .spawn()
        .expect("cablecell starts");
    let mut child = Killed(child);

    // The server is up once the port answers (generous: a cold start).
    let deadline = Instant::now() + Duration::from_secs(60);
    let stream = loop {
        match TcpStream::connect(&addr) {
            Ok(stream) => break stream,
            Err(_) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
            Err(error) => panic!("no server on {addr}: {error}"),
        }
    };
    stream
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let mut request =
        tungstenite::client::IntoClientRequest::into_client_request(format!("ws://{addr}"))
            .unwrap();
    request
        .headers_mut()
        .insert("Sec-WebSocket-Protocol", "foxglove.sdk.v1".parse().unwrap());
    let (mut socket, response) = tungstenite::client(request, stream).expect("a WebSocket");
    // Foxglove's WebSocket protocol v1, as the `foxglove` crate 0.30
    // names it (older servers called it `foxglove.websocket.v1`).
    assert_eq!(
        response.headers()["Sec-WebSocket-Protocol"],
        "foxglove.sdk.v1"
    );

    // Every channel is advertised as the viewer connects: subscribe to
    // the wanted ones as they appear, and read until the run ends and the
    // server closes.
    let wanted = ["/tactile/dv", "/state"];
    let mut subscriptions: BTreeMap<u32, String> = BTreeMap::new();
    let mut advertised = Vec::new();
    let mut received: BTreeMap<String, Vec<Value>> = BTreeMap::new();
    loop {
        let message = match socket.read() {
            Ok(message) => message,
            Err(tungstenite::Error::Io(e))
                if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::TimedOut =>
            {
                panic!("nothing for 30 s; advertised {advertised:?}, received {received:?}")
            }
            // The run ended and the server went away.
            Err(_) => break,
        };
        match message {
            tungstenite::Message::Text(text) => {
                let value: Value = serde_json::from_str(&text).unwrap();
                if value["op"] != "advertise" {
                    continue;
                }
                for channel in value["channels"].as_array().unwrap() {
                    let topic = channel["topic"].as_str().unwrap().to_owned();
                    advertised.push(topic.clone());
                    if !wanted.contains(&topic.as_str()) {
                        continue;
                    }
                    assert_eq!(channel["encoding"], "json");
                    assert!(
                        channel["schemaName"]
                            .as_str()
                            .unwrap()
                            .starts_with("cablecell.")
                    );
                    let id = subscriptions.len() as u32 + 1;
                    subscriptions.insert(id, topic);
                    let subscribe = serde_json::json!({
                        "op": "subscribe",
                        "subscriptions": [{"id": id, "channelId": channel["id"]}],
                    });
                    socket
                        .send(tungstenite::Message::text(subscribe.to_string()))
                        .unwrap();
                }
            }
            tungstenite::Message::Binary(bytes) => {
                // opcode 1 (message data), subscription id, log time, payload.
                if bytes.first() != Some(&1) || bytes.len() < 13 {
                    continue;
                }
                let id = u32::from_le_bytes(bytes[1..5].try_into().unwrap());
                let log_time_ns = u64::from_le_bytes(bytes[5..13].try_into().unwrap());
                assert!(
                    log_time_ns > 1_700_000_000 * 1_000_000_000,
                    "a wall-clock time"
                );
                let payload: Value = serde_json::from_slice(&bytes[13..]).unwrap();
                received
                    .entry(subscriptions[&id].clone())
                    .or_default()
                    .push(payload);
            }
            _ => {}
        }
    }
    let mut every_topic: Vec<&str> = cablecell::recording::Topic::ALL
        .iter()
        .map(|t| t.name())
        .collect();
    every_topic.sort();
    advertised.sort();
    assert_eq!(advertised, every_topic);
    assert!(child.0.wait().unwrap().success());

    // The viewer connected while the run prepared: it saw the trial
    // grasp's tactile frames (read in `evaluate`, the channel's first
    // messages) and every transition from then on, the last one too.
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(&report_path).unwrap()).unwrap();
    let sent: Vec<[&Value; 2]> = report["transitions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| [&t["from"], &t["to"]])
        .collect();
    let states = &received["/state"];
    assert!(!states.is_empty());
    let seen: Vec<[&Value; 2]> = states.iter().map(|s| [&s["from"], &s["to"]]).collect();
    assert!(sent.ends_with(&seen), "sent {sent:?}, seen {seen:?}");
    let frames = &received["/tactile/dv"];
    assert!(
        frames
            .iter()
            .all(|f| f["dv_v"].as_array().unwrap().len() == 25)
    );
    let grasped: Vec<&str> = frames
        .iter()
        .map(|f| f["state"].as_str().unwrap())
        .collect();
    assert!(grasped.contains(&"evaluate"), "{grasped:?}");
}

#[test]
fn the_layout_shows_only_channels_recordings_have() {
    let layout: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("docs/foxglove-layout.json")).unwrap(),
    )
    .unwrap();
    let names: Vec<&str> = cablecell::recording::Topic::ALL
        .iter()
        .map(|t| t.name())
        .collect();
    let mut seen = Vec::new();
    fn topics(value: &Value, seen: &mut Vec<String>) {
        match value {
            Value::String(s) if s.starts_with('/') => {
                // A message path: the topic, then `.field`.
                seen.push(s.split('.').next().unwrap_or(s).to_owned());
            }
            Value::Object(fields) => {
                for (key, value) in fields {
                    if key.starts_with('/') {
                        seen.push(key.clone());
                    }
                    topics(value, seen);
                }
            }
            Value::Array(items) => items.iter().for_each(|v| topics(v, seen)),
            _ => {}
        }
    }
    topics(&layout["configById"], &mut seen);
    assert!(seen.len() >= 8, "{seen:?}");
    for topic in &seen {
        assert!(names.contains(&topic.as_str()), "{topic} is no channel");
    }
}
