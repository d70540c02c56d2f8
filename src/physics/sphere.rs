//! Rigid-body counterpart of the sphere system (in progress).
