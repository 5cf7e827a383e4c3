//! A loaded project: profiles, corpus and the backends to run, from the usual folders.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::backend::{reference_backends, Backend};
use crate::load::{load_corpus, load_profiles, LoadErrors};
use crate::model::Corpus;
use crate::profile::Profiles;

/// Where a project keeps its data.
#[derive(Debug, Clone)]
pub struct Paths {
    pub vendors: PathBuf,
    pub vectors: Vec<PathBuf>,
}

impl Paths {
    /// `vendors/` and `vectors/` under a project root.
    pub fn under(root: &Path) -> Self {
        Paths {
            vendors: root.join("vendors"),
            vectors: vec![root.join("vectors")],
        }
    }
}

pub struct Session {
    pub profiles: Profiles,
    pub corpus: Corpus,
    pub backends: Vec<Arc<dyn Backend>>,
}

impl Session {
    /// Loads profiles and corpus and sets up the built-in reference backends.
    pub fn load(paths: &Paths) -> Result<Session, LoadErrors> {
        let profiles = load_profiles(&paths.vendors)?;
        let corpus = load_corpus(&paths.vectors, &profiles)?;
        let backends = reference_backends(&profiles);
        Ok(Session {
            profiles,
            corpus,
            backends,
        })
    }
}
