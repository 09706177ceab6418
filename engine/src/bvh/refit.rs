//! (issue 3) per-frame refit of deformed meshes with a SAH quality guard.
