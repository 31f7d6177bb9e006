//! The Chrome-trace timeline of every system call (`kdmpm run --trace FILE`, opened in
//! chrome://tracing or Perfetto), written from the schedule's spans when the crate is built
//! with the `trace` feature.

/// Starts writing the timeline to `path`; the returned guard flushes the file when dropped.
#[cfg(feature = "trace")]
pub fn start(path: std::path::PathBuf) -> Result<Box<dyn std::any::Any>, String> {
    use tracing_subscriber::prelude::*;
    let (layer, guard) = tracing_chrome::ChromeLayerBuilder::new()
        .file(path)
        .include_args(true)
        .build();
    tracing_subscriber::registry()
        .with(layer)
        .try_init()
        .map_err(|e| e.to_string())?;
    Ok(Box::new(guard))
}

/// Without the `trace` feature there are no spans to write: says how to build with them.
#[cfg(not(feature = "trace"))]
pub fn start(_path: std::path::PathBuf) -> Result<Box<dyn std::any::Any>, String> {
    Err(
        "--trace needs kdmpm built with the `trace` feature: cargo run --release --features trace -- run ..."
            .into(),
    )
}
