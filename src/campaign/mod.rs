//! Campaigns: many seeded trials of a task, each policy of the campaign
//! file on identical trials, recorded as they finish (`journal`), and
//! summarised (`stats`, `summary`); the bench's settings against their
//! costs (`bench`).

pub mod bench;
pub mod journal;
pub mod merge;
pub mod run;
pub mod shard;
pub mod stats;
pub mod summary;
pub mod trial;
