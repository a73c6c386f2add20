use asperity::{Error, Result};

#[derive(clap::Args)]
pub struct CalibrateArgs {}

pub fn run(_args: CalibrateArgs) -> Result<()> {
    Err(Error::Data("`calibrate` is not implemented yet".into()))
}
