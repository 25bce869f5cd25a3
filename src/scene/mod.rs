//! Scenes: what the user asks for (bodies, obstacles, laws, scheme, time), validated
//! and turned into a model plus an integrator.
//!
//! [`bar`] is the built-in reference scene: the paper's impacting elastic bar.
//! TOML scene files and meshes come with the solid-mesh work.

pub mod bar;
pub mod file;
pub mod solid_bar;
