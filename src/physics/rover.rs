//! Rigid-body counterpart of the rover system (in progress).
