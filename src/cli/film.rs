use asperity::{Error, Result};

#[derive(clap::Args)]
pub struct FilmArgs {}

pub fn run(_args: FilmArgs) -> Result<()> {
    Err(Error::Data("`film` is not implemented yet".into()))
}
