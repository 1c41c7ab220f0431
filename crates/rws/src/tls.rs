//! HTTPS (feature `tls`): the client's certificate check and the simulator's server side.
//!
//! The client accepts the controller's certificate when its SHA-256 equals the controller
//! file's `tls.pin_sha256` ([`CertPin`]): names and dates are not checked then, since the pin
//! names the one certificate and OmniCore's self-signed certificate is issued to no address
//! the cell uses. Without a pin it checks the certificate against the public web roots, as a
//! browser would (a controller with a certificate from a public CA). Either way a refused
//! certificate is kept with its fingerprint, so the error names what was expected and seen.
//! The handshake's signatures are checked by rustls' own verifier in both cases.

use std::sync::{Arc, Mutex};

use rustls::client::danger::{HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier};
use rustls::client::WebPkiServerVerifier;
use rustls::pki_types::{CertificateDer, PrivateKeyDer, ServerName, UnixTime};
use rustls::{CertificateError, DigitallySignedStruct, SignatureScheme};

use crate::pin::CertPin;

/// Why the verifier refused a certificate, kept for the client's error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Refusal {
    /// A pin was given and the certificate is another one.
    Mismatch {
        /// The controller file's pin.
        expected: CertPin,
        /// The certificate presented.
        seen: CertPin,
    },
    /// No pin, and the public roots do not vouch for the certificate.
    Untrusted {
        /// rustls' reason.
        reason: String,
        /// The certificate presented.
        seen: CertPin,
    },
}

/// The last refusal of one client's verifier.
pub(crate) type RefusalSlot = Arc<Mutex<Option<Refusal>>>;

#[derive(Debug)]
struct Verifier {
    pin: Option<CertPin>,
    webpki: Arc<WebPkiServerVerifier>,
    refused: RefusalSlot,
}

impl Verifier {
    fn refuse(&self, refusal: Refusal) {
        *self
            .refused
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(refusal);
    }
}

impl ServerCertVerifier for Verifier {
    fn verify_server_cert(
        &self,
        end_entity: &CertificateDer<'_>,
        intermediates: &[CertificateDer<'_>],
        server_name: &ServerName<'_>,
        ocsp_response: &[u8],
        now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        let seen = CertPin::of_der(end_entity);
        match self.pin {
            Some(expected) if expected == seen => Ok(ServerCertVerified::assertion()),
            Some(expected) => {
                self.refuse(Refusal::Mismatch { expected, seen });
                Err(rustls::Error::InvalidCertificate(
                    CertificateError::ApplicationVerificationFailure,
                ))
            }
            None => self
                .webpki
                .verify_server_cert(end_entity, intermediates, server_name, ocsp_response, now)
                .inspect_err(|e| {
                    self.refuse(Refusal::Untrusted {
                        reason: e.to_string(),
                        seen,
                    })
                }),
        }
    }

    fn verify_tls12_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        self.webpki.verify_tls12_signature(message, cert, dss)
    }

    fn verify_tls13_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        self.webpki.verify_tls13_signature(message, cert, dss)
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        self.webpki.supported_verify_schemes()
    }
}

fn provider() -> Arc<rustls::crypto::CryptoProvider> {
    Arc::new(rustls::crypto::ring::default_provider())
}

/// The client's TLS configuration for `pin` (module docs), and the slot its refusals go to.
///
/// # Errors
/// rustls refuses the protocol versions or the root store (not expected with ring).
pub(crate) fn client_config(
    pin: Option<CertPin>,
) -> Result<(rustls::ClientConfig, RefusalSlot), String> {
    let mut roots = rustls::RootCertStore::empty();
    roots.extend(webpki_roots::TLS_SERVER_ROOTS.iter().cloned());
    let webpki = WebPkiServerVerifier::builder_with_provider(Arc::new(roots), provider())
        .build()
        .map_err(|e| format!("TLS certificate verifier: {e}"))?;
    let refused = RefusalSlot::default();
    let verifier = Verifier {
        pin,
        webpki,
        refused: refused.clone(),
    };
    let config = rustls::ClientConfig::builder_with_provider(provider())
        .with_safe_default_protocol_versions()
        .map_err(|e| format!("TLS versions: {e}"))?
        .dangerous()
        .with_custom_certificate_verifier(Arc::new(verifier))
        .with_no_client_auth();
    Ok((config, refused))
}

/// The simulator's TLS acceptor for a PEM certificate (the leaf first) and PEM private key.
///
/// # Errors
/// Unreadable PEM, or a key that does not fit the certificate.
pub(crate) fn acceptor(
    cert_pem: &[u8],
    key_pem: &[u8],
) -> Result<tokio_rustls::TlsAcceptor, String> {
    use rustls::pki_types::pem::PemObject;
    let certs = CertificateDer::pem_slice_iter(cert_pem)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("certificate PEM: {e}"))?;
    if certs.is_empty() {
        return Err("certificate PEM: no CERTIFICATE block".into());
    }
    let key = PrivateKeyDer::from_pem_slice(key_pem).map_err(|e| format!("key PEM: {e}"))?;
    let config = rustls::ServerConfig::builder_with_provider(provider())
        .with_safe_default_protocol_versions()
        .map_err(|e| format!("TLS versions: {e}"))?
        .with_no_client_auth()
        .with_single_cert(certs, key)
        .map_err(|e| format!("certificate and key: {e}"))?;
    Ok(tokio_rustls::TlsAcceptor::from(Arc::new(config)))
}
