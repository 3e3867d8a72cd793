//! What every `--json` prints: one JSON object whose first field,
//! `schema_version`, says which version of cablecell's JSON outputs it
//! follows, with lengths in millimetres, angles in radians, times in
//! seconds (or milliseconds where the name says `_ms`) and rotations as
//! quaternions x, y, z, w. `cablecell json-schema OUTPUT` prints each
//! output's JSON Schema, derived from the types that print it;
//! `docs/schemas/` holds them all.

use schemars::{JsonSchema, Schema, schema_for};
use serde::Serialize;

use super::Status;

/// The version of cablecell's JSON outputs: raised when a field is
/// renamed, removed or changes its meaning, not when one is added.
pub const SCHEMA_VERSION: u32 = 1;

/// An output with its schema version in front.
#[derive(Serialize, JsonSchema)]
pub struct Versioned<T> {
    /// The version of cablecell's JSON outputs this follows.
    pub schema_version: u32,
    #[serde(flatten)]
    pub body: T,
}

/// Prints `body` as one pretty JSON object with the schema version; a
/// body that cannot be written as JSON (a bug) is an output failure.
pub fn print(body: impl Serialize) -> Status {
    let versioned = Versioned {
        schema_version: SCHEMA_VERSION,
        body,
    };
    match serde_json::to_string_pretty(&versioned) {
        Ok(text) => {
            super::output::line(format_args!("{text}"));
            Status::Success
        }
        Err(error) => {
            eprintln!("error: cannot write the output as JSON: {error}");
            Status::OutputFailed
        }
    }
}

/// Every command output that `--json` (or `tactile-fit`) prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum JsonOutput {
    /// `run --json`: the run record with each state's timing.
    Run,
    /// `campaign --json` and `campaign merge --json`: the summary.
    Campaign,
    /// `bench --json`: stage latencies and each setting's error and cost.
    Bench,
    /// `detect --json`: each image's cables.
    Detect,
    /// `eval-vision --json`: the scores against the labels.
    EvalVision,
    /// `eval-vision --sweep --json`: one row per setting.
    EvalVisionSweep,
    /// `tactile-fit`: the paper's wire parameters of one map.
    TactileFit,
    /// `device tactile … read --json`: the sensor's frames.
    DeviceTactileRead,
}

impl JsonOutput {
    /// The command line that prints it.
    fn command(self) -> &'static str {
        use JsonOutput::*;
        match self {
            Run => "cablecell run --json",
            Campaign => "cablecell campaign --json",
            Bench => "cablecell bench --json",
            Detect => "cablecell detect --json",
            EvalVision => "cablecell eval-vision --json",
            EvalVisionSweep => "cablecell eval-vision --sweep --json",
            TactileFit => "cablecell tactile-fit",
            DeviceTactileRead => "cablecell device tactile read --json",
        }
    }

    /// The output's JSON Schema, titled by its command line, with this
    /// version of the outputs as the only `schema_version` it allows.
    pub fn schema(self) -> Schema {
        let mut schema = self.body_schema();
        schema.insert("title".into(), self.command().into());
        schema.remove("description");
        if let Some(version) = schema
            .get_mut("properties")
            .and_then(|properties| properties.get_mut("schema_version"))
            .and_then(|version| version.as_object_mut())
        {
            version.insert("const".into(), SCHEMA_VERSION.into());
        }
        schema
    }

    fn body_schema(self) -> Schema {
        use JsonOutput::*;
        match self {
            Run => schema_for!(Versioned<cablecell::record::RunReport<'static>>),
            Campaign => schema_for!(Versioned<cablecell::campaign::summary::CampaignSummary>),
            Bench => schema_for!(Versioned<super::bench::BenchReport>),
            Detect => schema_for!(Versioned<super::detect::DetectReport>),
            EvalVision => schema_for!(Versioned<super::eval_vision::Report>),
            EvalVisionSweep => schema_for!(Versioned<super::eval_vision::sweep::Sweep>),
            TactileFit => schema_for!(Versioned<cablecell::perception::tactile::WireFit>),
            DeviceTactileRead => schema_for!(Versioned<super::device::TactileReading>),
        }
    }
}

/// `cablecell json-schema OUTPUT`
pub fn json_schema(output: JsonOutput) -> Status {
    match serde_json::to_string_pretty(&output.schema()) {
        Ok(text) => {
            super::output::line(format_args!("{text}"));
            Status::Success
        }
        Err(error) => {
            eprintln!("error: cannot write the schema: {error}");
            Status::OutputFailed
        }
    }
}
