//! The integration tests of hb-pipeline: the whole analysis of a record and its setups, the
//! comparison of a model with a record, the options of the requests and result files, and the
//! simulated systems of two coordinates.
//!
//! One test binary for the whole package: each file is a module of this one, so the crates they
//! share (the pipeline's stages, serde) are linked once, not once per file.
mod compare;
mod options;
mod output;
mod pipeline;
mod setup;
mod simulate;
