//! A loaded project: the vendor profiles and the corpus, and the known differences of the
//! backends set up so far. What a run plans from; the backends themselves are set up by
//! [`crate::session`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::backend::Backend;
use crate::load::{
    embedded_vectors, embedded_vendors, load_corpus, load_known, load_profiles, LoadErrors,
};
use crate::model::known::KnownDifferences;
use crate::model::profile::{Profile, Profiles};
use crate::model::Corpus;
use crate::plan::{plan, Trial};

/// Where a project keeps its data.
#[derive(Debug, Clone)]
pub struct Paths {
    /// The folder of vendor profiles (`vendors/<id>.yaml`).
    pub vendors: PathBuf,
    /// The vector folders and files the corpus is read from.
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

    /// The vendor profiles and corpus shipped inside the binary.
    pub fn embedded() -> Self {
        Paths {
            vendors: embedded_vendors(),
            vectors: vec![embedded_vectors()],
        }
    }

    /// A project folder's `vendors/` and `vectors/`, each replaced by the shipped one where the
    /// folder has none (a project that only lists its own backends runs the shipped corpus).
    pub fn of_project(root: &Path) -> Self {
        let (vendors, vectors) = (root.join("vendors"), root.join("vectors"));
        Paths {
            vendors: if vendors.is_dir() {
                vendors
            } else {
                embedded_vendors()
            },
            vectors: vec![if vectors.is_dir() {
                vectors
            } else {
                embedded_vectors()
            }],
        }
    }
}

/// A loaded project: what a run plans from.
pub struct Project {
    pub(crate) profiles: Profiles,
    /// Every case loaded: native, cross-vendor and protocol-field.
    pub corpus: Corpus,
    /// Known differences by backend name.
    pub known: BTreeMap<String, KnownDifferences>,
}

impl Project {
    /// The vendor profile of an id (`mitsubishi-iqr`).
    pub fn profile(&self, id: &str) -> Option<&Arc<Profile>> {
        self.profiles.get(id)
    }

    /// Every profile loaded, for this repository's tests and benchmarks.
    #[cfg(feature = "cli")]
    #[doc(hidden)]
    pub fn profiles(&self) -> &Profiles {
        &self.profiles
    }

    /// A project of profiles and a corpus loaded apart, with no known differences, for this
    /// repository's tests.
    #[cfg(feature = "cli")]
    #[doc(hidden)]
    pub fn from_parts(profiles: Profiles, corpus: Corpus) -> Project {
        Project {
            profiles,
            corpus,
            known: BTreeMap::new(),
        }
    }

    /// Loads profiles and corpus.
    pub fn load(paths: &Paths) -> Result<Project, LoadErrors> {
        let profiles = load_profiles(&paths.vendors)?;
        let corpus = load_corpus(&paths.vectors, &profiles)?;
        Ok(Project {
            profiles,
            corpus,
            known: BTreeMap::new(),
        })
    }

    /// Loads `file` as backend `name`'s known differences, checked against its profile (none,
    /// or an empty id, for a codec-level backend) and the corpus: the one place a project takes
    /// a known-differences file. `strict_known` makes an entry for a case outside the corpus
    /// an error (see [`load_known`]).
    pub(crate) fn add_known(
        &mut self,
        name: &str,
        profile: &str,
        file: &Path,
        strict_known: bool,
    ) -> Result<(), LoadErrors> {
        let known = self.read_known(profile, file, strict_known)?;
        self.known.insert(name.to_string(), known);
        Ok(())
    }

    fn read_known(
        &self,
        profile: &str,
        file: &Path,
        strict_known: bool,
    ) -> Result<KnownDifferences, LoadErrors> {
        let profile = self.profiles.get(profile).map(|p| p.as_ref());
        load_known(file, profile, &self.corpus, strict_known)
    }

    /// A known-differences file for `backend`, checked against its profile (none for a codec)
    /// and the whole corpus: an entry for a case the corpus does not have is an error.
    pub fn known_differences(
        &self,
        backend: &dyn Backend,
        file: &Path,
    ) -> Result<KnownDifferences, LoadErrors> {
        self.read_known(backend.profile(), file, true)
    }

    /// Every trial of the corpus on these backends, with their known differences.
    pub fn plan(&self, backends: &[Arc<dyn Backend>]) -> Vec<Trial> {
        plan(&self.corpus, &self.profiles, backends, &self.known)
    }
}
