use asperity::{Error, Result};

#[derive(clap::Args)]
pub struct ElementsArgs {}

pub fn run(_args: ElementsArgs) -> Result<()> {
    Err(Error::Data("`elements` is not implemented yet".into()))
}
