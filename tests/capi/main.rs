//! The C API as hosts use it: the checked-in bindings, the library loaded
//! at run time, introspection, and the C and C++ host programs of `c/`
//! built with the system compiler against the library cargo built.

#[path = "../common/mod.rs"]
mod common;

mod autostereo_host;
mod big_grid;
mod bindings;
mod deadline_host;
mod dlopen;
mod host_patterns;
mod hostile_host;
mod hosts;
mod info;
mod python_host;
mod units_host;
