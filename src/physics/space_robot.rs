//! Rigid-body counterpart of the space_robot system (in progress).
