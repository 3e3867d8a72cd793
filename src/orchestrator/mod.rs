//! The grasp sequence: a hierarchical state machine that does no I/O
//! (`machine`, which also names its states, once), the commands it asks
//! for and the events that answer them (`command`), the executor that
//! carries commands out on a cell (`executor`), the runner that feeds one
//! to the other (`runner`), and for the REPL the driver that steps, pauses,
//! breaks and aborts (`driver`, `breakpoint`) and the task's parameters
//! (`params`); `graph` draws the machine.

pub mod breakpoint;
pub mod command;
pub mod driver;
pub mod executor;
pub mod graph;
pub mod machine;
pub mod params;
pub mod plan;
pub mod runner;
#[cfg(test)]
mod test_cell;

pub use command::{Command, Event};
pub use machine::{Context, GraspTask, State, Superstate};
pub use plan::Plan;
pub use runner::Runner;
