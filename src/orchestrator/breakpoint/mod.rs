//! Breakpoints on a run: a state to stop in, and optionally a condition on
//! the run's named values (`abs(n_mm) > 2 and regrasps < 2`): the values a
//! run has (`values`), the language of conditions on them (`condition`),
//! and the breakpoints of a session (`registry`).
//!
//! The condition language is small on purpose: numbers, the names of
//! [`RunValues`], `+ - * /`, unary minus, `abs(...)`, parentheses, the
//! comparisons `< <= > >= == !=`, and `and` / `or` (`not` too). Names and
//! types are checked when the breakpoint is set, so a typo is an error then
//! and not a breakpoint that silently never fires.

mod condition;
mod registry;
mod values;

pub use condition::{Condition, ConditionError, MAX_TOKENS};
pub use registry::{Breakpoint, BreakpointError, Breakpoints};
pub use values::RunValues;
