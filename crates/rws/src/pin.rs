//! A pinned controller certificate: the SHA-256 fingerprint a controller file gives in
//! `tls: {pin_sha256: "3A:04:…"}`, spelled as `openssl x509 -noout -fingerprint -sha256` and
//! browsers print it (hex pairs, colons optional).
//!
//! OmniCore controllers (RobotWare 7, HTTPS only) ship a self-signed certificate that no public
//! root vouches for. Instead of accepting any certificate, the client accepts exactly the one
//! whose fingerprint is pinned (`crate::tls`): a man in the middle cannot present it.

use std::fmt;

use serde::Deserialize;

/// SHA-256 of a certificate's DER bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(try_from = "String")]
pub struct CertPin(pub [u8; 32]);

impl CertPin {
    /// Reads 32 bytes of hex: `3A:04:1F:…`, `3a041f…` or with spaces; an `openssl`
    /// `sha256 Fingerprint=` prefix is allowed.
    ///
    /// # Errors
    /// Not 64 hex digits, with the count found.
    pub fn parse(text: &str) -> Result<Self, String> {
        let trimmed = text.trim();
        let body = trimmed
            .split_once('=')
            .filter(|(head, _)| head.to_ascii_lowercase().contains("fingerprint"))
            .map_or(trimmed, |(_, fp)| fp);
        let digits: Vec<u8> = body
            .bytes()
            .filter(|b| !matches!(b, b':' | b' ' | b'-'))
            .collect();
        let nibble = |b: u8| (b as char).to_digit(16).map(|d| d as u8);
        if digits.len() != 64 || digits.iter().any(|b| nibble(*b).is_none()) {
            return Err(format!(
                "{text:?}: expected the certificate's SHA-256 fingerprint, 32 hex pairs such as \"3A:04:1F:…\" (found {} hex digits{})",
                digits.iter().filter(|b| nibble(**b).is_some()).count(),
                if digits.iter().any(|b| nibble(*b).is_none()) {
                    " and other characters"
                } else {
                    ""
                }
            ));
        }
        let mut out = [0u8; 32];
        for (i, pair) in digits.chunks(2).enumerate() {
            out[i] = nibble(pair[0]).unwrap_or(0) << 4 | nibble(pair[1]).unwrap_or(0);
        }
        Ok(CertPin(out))
    }

    /// The fingerprint of a certificate (DER).
    #[cfg(feature = "tls")]
    pub fn of_der(der: &[u8]) -> Self {
        let digest = ring::digest::digest(&ring::digest::SHA256, der);
        let mut out = [0u8; 32];
        out.copy_from_slice(digest.as_ref());
        CertPin(out)
    }
}

impl TryFrom<String> for CertPin {
    type Error = String;
    fn try_from(text: String) -> Result<Self, String> {
        CertPin::parse(&text)
    }
}

impl fmt::Display for CertPin {
    /// Upper-case hex pairs joined by colons, as `openssl` prints them.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, b) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(":")?;
            }
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

impl fmt::Debug for CertPin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "CertPin({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OPENSSL: &str = "3A:04:1F:B9:6B:6C:96:35:CD:43:A4:A6:91:31:B8:2D:34:55:F5:ED:6B:36:60:E1:E7:6D:5E:31:70:A6:84:43";

    #[test]
    fn reads_the_usual_spellings_and_prints_openssls() {
        let pin = CertPin::parse(OPENSSL).unwrap();
        assert_eq!(pin.to_string(), OPENSSL);
        let bare = OPENSSL.replace(':', "").to_lowercase();
        assert_eq!(CertPin::parse(&bare).unwrap(), pin);
        assert_eq!(
            CertPin::parse(&format!("sha256 Fingerprint={OPENSSL}")).unwrap(),
            pin
        );
    }

    #[test]
    fn refuses_what_is_not_a_sha256() {
        let e = CertPin::parse("AB:CD").unwrap_err();
        assert!(e.contains("found 4 hex digits"), "{e}");
        let e = CertPin::parse(&OPENSSL.replace("3A", "ZZ")).unwrap_err();
        assert!(e.contains("other characters"), "{e}");
    }
}
