//! No code. Depending on this crate pins the features of dependencies shared by the root
//! workspace and the Python extension's workspace, so both reuse one build of each (see this
//! crate's Cargo.toml for why and how to keep the list right).
