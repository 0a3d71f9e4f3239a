#[derive(Debug, thiserror::Error)] #[error("out")] pub struct OutputError;
