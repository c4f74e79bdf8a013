//! The package's calls, one file per command as the command line's `src/cli/command/`: each
//! a function of the model and the call's arguments, bound as a method of `NativeModel`.

pub(crate) mod allocate;
pub(crate) mod analyze;
pub(crate) mod frf;
pub(crate) mod merge;
pub(crate) mod modal;
pub(crate) mod model_info;
pub(crate) mod sensitivity;
pub(crate) mod sweep;
