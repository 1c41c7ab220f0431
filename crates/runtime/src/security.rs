//! DDS Security (SROS2) from the ROS 2 environment, read the way rcl reads it
//! (`rcl/src/rcl/security.c`, `rcl_get_security_options_from_environment`, `rcl_get_secure_root`):
//!
//! - `ROS_SECURITY_ENABLE=true` turns security on; any other value leaves it off.
//! - `ROS_SECURITY_STRATEGY=Enforce` refuses to start without the enclave's files;
//!   `Permissive` (or unset) runs unsecured, with a warning, when they are missing.
//! - `ROS_SECURITY_KEYSTORE` is the keystore; the enclave is `--ros-args --enclave /x` (`/` when
//!   not given), which `ROS_SECURITY_ENCLAVE_OVERRIDE` replaces; its files live in
//!   `<keystore>/enclaves/<enclave>`, with the names rmw_dds_common's `security.cpp` gives them
//!   ([`ENCLAVE_FILES`]). `scripts/sros2_keystore.sh` (or `ros2 security create_keystore` and
//!   `create_enclave`) makes such a keystore.
//!
//! Unlike rcl, a strategy other than `Enforce`/`Permissive` is an error rather than Permissive,
//! and a build without the `security` feature refuses `ROS_SECURITY_ENABLE=true` outright:
//! a node never starts unsecured when it was asked to be secured and could not say why.

use std::path::{Path, PathBuf};

use anyhow::bail;

/// The files of an enclave, as rmw_dds_common names them (and rustdds'
/// `DomainParticipantSecurityConfigFiles::with_ros_default_names` reads them): identity CA,
/// the participant's certificate and private key (PKCS#8, unencrypted), permissions CA, signed
/// governance and signed permissions (S/MIME).
pub const ENCLAVE_FILES: [&str; 6] = [
    "identity_ca.cert.pem",
    "cert.pem",
    "key.pem",
    "permissions_ca.cert.pem",
    "governance.p7s",
    "permissions.p7s",
];

/// What to do when the enclave's files are missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// Refuse to start.
    Enforce,
    /// Start unsecured, with a warning.
    Permissive,
}

/// The `ROS_SECURITY_*` variables, read once so the rules below are testable without touching
/// the process environment.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SecurityEnv {
    /// `ROS_SECURITY_ENABLE`.
    pub enable: Option<String>,
    /// `ROS_SECURITY_STRATEGY`.
    pub strategy: Option<String>,
    /// `ROS_SECURITY_KEYSTORE`.
    pub keystore: Option<String>,
    /// `ROS_SECURITY_ENCLAVE_OVERRIDE`.
    pub enclave_override: Option<String>,
}

impl SecurityEnv {
    /// The process environment's values (empty values count as unset).
    pub fn from_env() -> Self {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
        Self {
            enable: var("ROS_SECURITY_ENABLE"),
            strategy: var("ROS_SECURITY_STRATEGY"),
            keystore: var("ROS_SECURITY_KEYSTORE"),
            enclave_override: var("ROS_SECURITY_ENCLAVE_OVERRIDE"),
        }
    }

    /// The enclave directory whose files secure the node, or `None` when the node runs
    /// unsecured (security off, or Permissive with files missing, which is logged). `enclave` is
    /// the `--enclave` argument. Errors name the variable or file at fault.
    pub fn enclave_dir(&self, enclave: Option<&str>) -> anyhow::Result<Option<PathBuf>> {
        if self.enable.as_deref() != Some("true") {
            return Ok(None);
        }
        if !cfg!(feature = "security") {
            bail!(
                "ROS_SECURITY_ENABLE=true, but this build has no DDS Security: rebuild with \
                 `--features security` (README \"Security (SROS2)\") or unset ROS_SECURITY_ENABLE"
            );
        }
        let strategy = match self.strategy.as_deref() {
            None | Some("Permissive") => Strategy::Permissive,
            Some("Enforce") => Strategy::Enforce,
            Some(other) => {
                bail!("ROS_SECURITY_STRATEGY={other:?}: expected Enforce or Permissive")
            }
        };
        let unsecured = |why: String| -> anyhow::Result<Option<PathBuf>> {
            match strategy {
                Strategy::Enforce => bail!("SROS2 (ROS_SECURITY_STRATEGY=Enforce): {why}"),
                Strategy::Permissive => {
                    tracing::warn!("SROS2 (Permissive): {why}; running UNSECURED");
                    Ok(None)
                }
            }
        };
        let Some(keystore) = self.keystore.as_deref() else {
            return unsecured(
                "ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is not set".into(),
            );
        };
        let enclave = self.enclave_override.as_deref().or(enclave).unwrap_or("/");
        if !enclave.starts_with('/') {
            bail!("enclave {enclave:?}: an enclave must be absolute (start with '/')");
        }
        let dir = Path::new(keystore)
            .join("enclaves")
            .join(enclave.trim_start_matches('/'));
        if !dir.is_dir() {
            return unsecured(format!(
                "no enclave {enclave} in keystore {keystore} ({} is not a directory)",
                dir.display()
            ));
        }
        let missing: Vec<String> = ENCLAVE_FILES
            .iter()
            .map(|f| dir.join(f))
            .filter(|p| !p.is_file())
            .map(|p| p.display().to_string())
            .collect();
        if !missing.is_empty() {
            return unsecured(format!(
                "enclave {enclave} lacks {} (keystore {keystore})",
                missing.join(", ")
            ));
        }
        Ok(Some(dir))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(strategy: &str, keystore: &Path) -> SecurityEnv {
        SecurityEnv {
            enable: Some("true".into()),
            strategy: Some(strategy.into()),
            keystore: Some(keystore.display().to_string()),
            enclave_override: None,
        }
    }

    #[cfg(feature = "security")]
    fn enclave_with(keystore: &Path, enclave: &str, files: &[&str]) -> PathBuf {
        let dir = keystore
            .join("enclaves")
            .join(enclave.trim_start_matches('/'));
        std::fs::create_dir_all(&dir).unwrap();
        for f in files {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        dir
    }

    #[test]
    fn off_unless_enable_is_exactly_true() {
        for enable in [None, Some("false"), Some("1"), Some("True")] {
            let e = SecurityEnv {
                enable: enable.map(String::from),
                strategy: Some("Enforce".into()),
                ..Default::default()
            };
            assert_eq!(e.enclave_dir(Some("/a")).unwrap(), None, "{enable:?}");
        }
    }

    #[cfg(not(feature = "security"))]
    #[test]
    fn a_build_without_the_feature_refuses_security() {
        let ks = tempfile::tempdir().unwrap();
        for strategy in ["Enforce", "Permissive"] {
            let err = env(strategy, ks.path()).enclave_dir(None).unwrap_err();
            assert!(err.to_string().contains("--features security"), "{err}");
        }
    }

    #[cfg(feature = "security")]
    #[test]
    fn enforce_names_the_missing_file_and_permissive_runs_unsecured() {
        let ks = tempfile::tempdir().unwrap();
        let dir = enclave_with(ks.path(), "/cell/probe", &ENCLAVE_FILES[..5]);
        let err = env("Enforce", ks.path())
            .enclave_dir(Some("/cell/probe"))
            .unwrap_err()
            .to_string();
        let missing = dir.join("permissions.p7s").display().to_string();
        assert!(err.contains(&missing), "{err}");
        assert!(!err.contains("governance.p7s"), "{err}");
        assert_eq!(
            env("Permissive", ks.path())
                .enclave_dir(Some("/cell/probe"))
                .unwrap(),
            None
        );
        let err = env("Enforce", ks.path())
            .enclave_dir(Some("/nope"))
            .unwrap_err();
        assert!(err.to_string().contains("no enclave /nope"), "{err}");
        let err = env("enforce", ks.path()).enclave_dir(None).unwrap_err();
        assert!(
            err.to_string().contains("expected Enforce or Permissive"),
            "{err}"
        );
    }

    #[cfg(feature = "security")]
    #[test]
    fn the_override_replaces_the_enclave_argument() {
        let ks = tempfile::tempdir().unwrap();
        let dir = enclave_with(ks.path(), "/over", &ENCLAVE_FILES);
        enclave_with(ks.path(), "/arg", &ENCLAVE_FILES);
        let mut e = env("Enforce", ks.path());
        e.enclave_override = Some("/over".into());
        assert_eq!(e.enclave_dir(Some("/arg")).unwrap(), Some(dir));
        e.keystore = None;
        let err = e.enclave_dir(Some("/arg")).unwrap_err();
        assert!(err.to_string().contains("ROS_SECURITY_KEYSTORE"), "{err}");
    }
}
