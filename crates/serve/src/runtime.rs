//! The tokio runtime a server runs on: two workers for the network, as
//! rendering runs on the rayon pool.

use anyhow::{Context, Result};

/// A tokio runtime for the server (rendering runs on the rayon pool).
pub fn runtime() -> Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("cannot start the async runtime")
}
