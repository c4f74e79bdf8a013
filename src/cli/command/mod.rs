//! One file per subcommand: each reads its inputs, calls the library and writes what it
//! returns.

mod allocate;
mod analyze;
mod check;
mod draw;
mod frf;
mod merge;
mod modal;
mod sensitivity;
mod sweep;

pub(crate) use allocate::allocate_command;
pub(crate) use analyze::analyze_command;
pub(crate) use check::check_command;
pub(crate) use draw::draw_command;
pub(crate) use frf::frf_command;
pub(crate) use merge::merge_command;
pub(crate) use modal::modal_command;
pub(crate) use sensitivity::sensitivity_command;
pub(crate) use sweep::sweep_command;
