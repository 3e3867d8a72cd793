//! The grasp sequence: a hierarchical state machine that does no I/O
//! (`machine`, which also names its states, once), the commands it asks
//! for and the events that answer them (`command`), the executor that
//! carries commands out on a cell (`executor`), the runner that feeds one
//! to the other (`runner`), and for the REPL the driver that steps, pauses,
//! breaks and aborts (`driver`, `breakpoint`) and the task's parameters
//! (`params`); `graph` draws the machine; `shapes` gives each grasp the
//! cable's shapes, seen, felt and fused.

pub mod breakpoint;
pub mod command;
pub mod driver;
pub mod executor;
pub mod graph;
pub mod machine;
pub mod params;
pub mod plan;
pub mod runner;
pub mod shapes;
#[cfg(test)]
mod test_cell;

pub use command::{Command, Event};
pub use machine::{Context, GraspTask, State, Superstate};
pub use plan::Plan;
pub use runner::Runner;
