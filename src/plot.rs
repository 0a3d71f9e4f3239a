#[derive(Debug, thiserror::Error)] #[error("plot")] pub struct PlotError;
