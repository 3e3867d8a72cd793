//! Reading the project's TOML files: every error names the file, line,
//! column and field; the range checks the fields' types use; a rigid
//! transform as the files write it. Each file's schema lives with what it
//! configures.

mod frame;
pub mod toml_file;
pub mod validate;

pub use frame::FrameConfig;
pub use toml_file::ConfigError;
