//! Physics world: URDF models in rapier3d, stepped at a fixed rate (being built).
