//! The grasp sequence: a hierarchical state machine that does no I/O
//! (`machine`), the commands it asks for and the events that answer them
//! (`command`), the executor that carries commands out on a cell
//! (`executor`), the runner that feeds one to the other (`runner`), and the
//! run record every run writes (`record`).

pub mod command;
pub mod executor;
pub mod machine;
pub mod plan;
pub mod record;
pub mod runner;

pub use command::{Command, Event};
pub use machine::{Context, GraspTask, State};
pub use plan::Plan;
pub use record::{RunOutcome, RunRecord};
pub use runner::Runner;
