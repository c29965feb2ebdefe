//! TLS for [`crate::PostgresStore`]: which connections are encrypted, and against which
//! certificate authorities the server is checked, read from libpq's URL parameters.
//!
//! - `sslmode=require`, `verify-ca` or `verify-full`, or `sslrootcert=FILE`, or a client
//!   certificate: every connection is TLS (rustls), and the server's certificate chain **and
//!   host name** are always checked (as libpq's `verify-full`: a certificate is never accepted
//!   unchecked), against the PEM certificates in `sslrootcert` or, without it, the public web
//!   CAs (`webpki-roots`: managed PostgreSQL and CockroachDB Cloud use those).
//! - `sslcert=FILE&sslkey=FILE` (PEM; both or neither): the client's certificate chain and
//!   private key, for servers that authenticate clients by certificate (PostgreSQL's `cert`
//!   method, CockroachDB's `client.USER.crt`).
//! - `sslmode=disable` or `prefer`, or none of the above: plain connections (as before).
//!
//! `sslrootcert`, `sslcert`, `sslkey` and the `verify-*` modes are libpq's, not the client's:
//! they are taken out of the URL before it is parsed.

use crate::StoreError;
use rustls::RootCertStore;
use rustls::pki_types::pem::PemObject;
use rustls::pki_types::{CertificateDer, PrivateKeyDer};
use std::sync::Arc;
use tokio_postgres_rustls::MakeRustlsConnect;

/// How a store's connections are made.
#[derive(Clone)]
pub(crate) enum Transport {
    /// Unencrypted (`sslmode` absent, `disable` or `prefer`).
    Plain,
    /// TLS, the server checked against the roots the URL asked for.
    Tls(MakeRustlsConnect),
}

/// A URL's TLS settings, taken out of it: the URL the client parses, and the transport.
pub(crate) struct Split {
    /// The URL the client parses: without `sslrootcert`, `sslcert` and `sslkey`, and with
    /// `sslmode=require` first when TLS is on (the `verify-*` modes become `require`: the
    /// check is rustls's, always).
    pub(crate) url: String,
    /// How to connect.
    pub(crate) transport: Transport,
    /// Where the roots come from, for messages: `the CA in FILE` or `the public web CAs`.
    pub(crate) roots: Option<String>,
}

/// Splits `url`'s TLS parameters off (module docs); `read` reads the files they name (the
/// store passes `std::fs::read`, tests a fake).
pub(crate) fn split(
    url: &str,
    mut read: impl FnMut(&str) -> std::io::Result<Vec<u8>>,
) -> Result<Split, StoreError> {
    // The query starts at the first `?` after the user and password (which may hold one).
    let after_user = url.rfind('@').map_or(0, |at| at + 1);
    let (base, query) = match url[after_user..].find('?') {
        Some(q) => (&url[..after_user + q], &url[after_user + q + 1..]),
        None => (url, ""),
    };
    let mut kept: Vec<String> = Vec::new();
    let mut sslmode: Option<String> = None;
    let (mut root_file, mut cert_file, mut key_file): (Option<String>, _, _) = (None, None, None);
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        let (raw_key, raw_value) = pair.split_once('=').unwrap_or((pair, ""));
        // Decoded as the client decodes the parameters it keeps (`%20` a space, `%26` an `&`).
        let decode = |text: &str| {
            percent_encoding::percent_decode_str(text)
                .decode_utf8()
                .map(|t| t.into_owned())
                .map_err(|_| {
                    StoreError::Address(format!("{raw_key}: not UTF-8 once percent-decoded"))
                })
        };
        let key = decode(raw_key)?;
        let file_slot = match key.as_str() {
            "sslrootcert" => &mut root_file,
            "sslcert" => &mut cert_file,
            "sslkey" => &mut key_file,
            "sslmode" => {
                let value = decode(raw_value)?;
                if !matches!(
                    value.as_str(),
                    "disable" | "prefer" | "require" | "verify-ca" | "verify-full"
                ) {
                    return Err(StoreError::Address(format!(
                        "sslmode={value}: expected disable, prefer, require, verify-ca or verify-full"
                    )));
                }
                if sslmode.replace(value).is_some() {
                    return Err(StoreError::Address(
                        "sslmode: given twice; expected it once".into(),
                    ));
                }
                // Its place, rewritten below.
                kept.push(pair.to_string());
                continue;
            }
            _ => {
                kept.push(pair.to_string());
                continue;
            }
        };
        let value = decode(raw_value)?;
        if value.is_empty() {
            return Err(StoreError::Address(format!(
                "{key}: expected the path of a PEM file"
            )));
        }
        if file_slot.replace(value).is_some() {
            return Err(StoreError::Address(format!(
                "{key}: given twice; expected it once"
            )));
        }
    }
    let files = root_file.is_some() || cert_file.is_some() || key_file.is_some();
    let tls = match sslmode.as_deref() {
        Some("require" | "verify-ca" | "verify-full") => true,
        Some(mode) if files => {
            return Err(StoreError::Address(format!(
                "sslmode={mode} with sslrootcert, sslcert or sslkey: expected sslmode=require \
                 (or none)"
            )));
        }
        Some(_) => false,
        None => files,
    };
    if tls {
        let mode = "sslmode=require".to_string();
        match kept.iter().position(|p| p.starts_with("sslmode=")) {
            Some(at) => kept[at] = mode,
            None => kept.push(mode),
        }
    }
    let client = match (cert_file, key_file) {
        (None, None) => None,
        (Some(cert), Some(key)) => Some((cert, key)),
        (Some(_), None) => {
            return Err(StoreError::Address(
                "sslcert without sslkey: expected both (the client's certificate and its key)"
                    .into(),
            ));
        }
        (None, Some(_)) => {
            return Err(StoreError::Address(
                "sslkey without sslcert: expected both (the client's certificate and its key)"
                    .into(),
            ));
        }
    };
    let url = if kept.is_empty() {
        base.to_string()
    } else {
        format!("{base}?{}", kept.join("&"))
    };
    if !tls {
        return Ok(Split {
            url,
            transport: Transport::Plain,
            roots: None,
        });
    }
    let (roots, from) = match &root_file {
        Some(file) => (
            roots_from_file(file, &mut read)?,
            format!("the CA in {file}"),
        ),
        None => (
            RootCertStore {
                roots: webpki_roots::TLS_SERVER_ROOTS.to_vec(),
            },
            "the public web CAs".to_string(),
        ),
    };
    // ring, not rustls's newer default aws-lc-rs (post-quantum key exchange): ring builds in
    // seconds with the C compiler SQLite's build already needs, aws-lc-rs in minutes.
    #[allow(deprecated)]
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let builder = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| StoreError::Address(format!("TLS: {e}")))?
        .with_root_certificates(roots);
    let config = match client {
        None => builder.with_no_client_auth(),
        Some((cert, key)) => {
            let chain = certificates(&cert, "sslcert", &mut read)?;
            let pem = read(&key)
                .map_err(|e| StoreError::Address(format!("sslkey {key}: cannot read it ({e})")))?;
            let private = PrivateKeyDer::from_pem_slice(&pem).map_err(|e| {
                StoreError::Address(format!(
                    "sslkey {key}: no private key in it (expected PEM: -----BEGIN PRIVATE KEY-----; {e})"
                ))
            })?;
            builder.with_client_auth_cert(chain, private).map_err(|e| {
                StoreError::Address(format!(
                    "sslcert {cert} with sslkey {key}: not a usable certificate and key ({e})"
                ))
            })?
        }
    };
    Ok(Split {
        url,
        transport: Transport::Tls(MakeRustlsConnect::new(config)),
        roots: Some(from),
    })
}

/// The certificates of the PEM file `file`, named by the URL's parameter `what`; at least one.
fn certificates(
    file: &str,
    what: &str,
    read: &mut impl FnMut(&str) -> std::io::Result<Vec<u8>>,
) -> Result<Vec<CertificateDer<'static>>, StoreError> {
    let pem = read(file)
        .map_err(|e| StoreError::Address(format!("{what} {file}: cannot read it ({e})")))?;
    let certs = CertificateDer::pem_slice_iter(&pem)
        .enumerate()
        .map(|(k, cert)| {
            cert.map_err(|e| {
                StoreError::Address(format!(
                    "{what} {file}: certificate {} is not valid PEM ({e})",
                    k + 1
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    if certs.is_empty() {
        return Err(StoreError::Address(format!(
            "{what} {file}: no certificate in it (expected PEM: -----BEGIN CERTIFICATE-----)"
        )));
    }
    Ok(certs)
}

/// The CA certificates of the PEM file `file`.
fn roots_from_file(
    file: &str,
    read: &mut impl FnMut(&str) -> std::io::Result<Vec<u8>>,
) -> Result<RootCertStore, StoreError> {
    let mut roots = RootCertStore::empty();
    for (k, cert) in certificates(file, "sslrootcert", read)?
        .into_iter()
        .enumerate()
    {
        roots.add(cert).map_err(|e| {
            StoreError::Address(format!(
                "sslrootcert {file}: certificate {} is not a usable CA certificate ({e})",
                k + 1
            ))
        })?;
    }
    Ok(roots)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_file(_: &str) -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::from(std::io::ErrorKind::NotFound))
    }

    fn address(r: Result<Split, StoreError>) -> String {
        match r {
            Err(StoreError::Address(why)) => why,
            Err(e) => panic!("not an address error: {e}"),
            Ok(s) => panic!("accepted: {}", s.url),
        }
    }

    #[test]
    fn plain_urls_pass_unchanged() {
        for url in [
            "postgres://u@h:5432/db",
            "postgres://u@h/db?connect_timeout=3",
            "postgres://u@h/db?sslmode=disable",
            "postgres://u@h/db?sslmode=prefer&application_name=x",
        ] {
            let s = split(url, no_file).unwrap();
            assert_eq!(s.url, url);
            assert!(matches!(s.transport, Transport::Plain));
            assert_eq!(s.roots, None);
        }
    }

    #[test]
    fn tls_modes_become_require_and_the_root_file_is_taken_out() {
        for (url, want) in [
            (
                "postgres://u@h/db?sslmode=require",
                "postgres://u@h/db?sslmode=require",
            ),
            (
                "postgres://u@h/db?sslmode=verify-full&connect_timeout=2",
                "postgres://u@h/db?sslmode=require&connect_timeout=2",
            ),
            (
                "postgres://u@h/db?sslmode=verify-ca",
                "postgres://u@h/db?sslmode=require",
            ),
        ] {
            let s = split(url, no_file).unwrap();
            assert_eq!(s.url, want);
            assert!(matches!(s.transport, Transport::Tls(_)));
            assert_eq!(s.roots.as_deref(), Some("the public web CAs"));
        }
    }

    #[test]
    fn a_root_file_is_read_and_names_itself() {
        // Not a CA the test checks against a server: only that PEM is read and kept.
        let pem = include_bytes!("../tests/data/test-ca.pem");
        let s = split(
            "postgres://u@h/db?sslrootcert=/etc/ca.pem&connect_timeout=2",
            |path| {
                assert_eq!(path, "/etc/ca.pem");
                Ok(pem.to_vec())
            },
        )
        .unwrap();
        assert_eq!(s.url, "postgres://u@h/db?connect_timeout=2&sslmode=require");
        assert_eq!(s.roots.as_deref(), Some("the CA in /etc/ca.pem"));
        // Decoded as the client decodes what it keeps; a `?` in the password is not the query.
        let s = split(
            "postgres://u:p?w@h/db?sslrootcert=%2Fmy%20certs%2Fca%26.pem",
            |path| {
                assert_eq!(path, "/my certs/ca&.pem");
                Ok(pem.to_vec())
            },
        )
        .unwrap();
        assert_eq!(s.url, "postgres://u:p?w@h/db?sslmode=require");
        assert_eq!(s.roots.as_deref(), Some("the CA in /my certs/ca&.pem"));
    }

    #[test]
    fn bad_tls_parameters_are_named() {
        let e = address(split("postgres://u@h/db?sslrootcert=/no/ca.pem", no_file));
        assert!(
            e.starts_with("sslrootcert /no/ca.pem: cannot read it"),
            "{e}"
        );
        let e = address(split("postgres://u@h/db?sslrootcert=/x.pem", |_| {
            Ok(b"not a certificate".to_vec())
        }));
        assert!(e.contains("/x.pem: no certificate in it"), "{e}");
        let e = address(split("postgres://u@h/db?sslrootcert=/x.pem", |_| {
            Ok(b"-----BEGIN CERTIFICATE-----\nAAAA\n-----END CERTIFICATE-----\n".to_vec())
        }));
        assert!(e.contains("/x.pem: certificate 1 is not"), "{e}");
        let e = address(split(
            "postgres://u@h/db?sslmode=require&sslmode=disable",
            no_file,
        ));
        assert!(e.starts_with("sslmode: given twice"), "{e}");
        let e = address(split(
            "postgres://u@h/db?sslrootcert=/a.pem&sslrootcert=/b.pem",
            no_file,
        ));
        assert!(e.starts_with("sslrootcert: given twice"), "{e}");
        let e = address(split("postgres://u@h/db?sslmode=allow", no_file));
        assert!(e.starts_with("sslmode=allow: expected disable"), "{e}");
        let e = address(split("postgres://u@h/db?sslrootcert=", no_file));
        assert!(e.starts_with("sslrootcert: expected the path"), "{e}");
        let e = address(split("postgres://u@h/db?sslcert=/c.pem", no_file));
        assert!(e.starts_with("sslcert without sslkey"), "{e}");
        let e = address(split("postgres://u@h/db?sslkey=/k.pem", no_file));
        assert!(e.starts_with("sslkey without sslcert"), "{e}");
        let e = address(split(
            "postgres://u@h/db?sslcert=/c.pem&sslkey=/k.pem",
            no_file,
        ));
        assert!(e.starts_with("sslcert /c.pem: cannot read it"), "{e}");
        let cert = include_bytes!("../tests/data/test-ca.pem");
        let e = address(split(
            "postgres://u@h/db?sslcert=/c.pem&sslkey=/k.pem",
            |path| match path {
                "/c.pem" => Ok(cert.to_vec()),
                _ => Ok(b"not a key".to_vec()),
            },
        ));
        assert!(e.starts_with("sslkey /k.pem: no private key in it"), "{e}");
        let e = address(split(
            "postgres://u@h/db?sslmode=disable&sslrootcert=/ca.pem",
            |_| Ok(Vec::new()),
        ));
        assert!(
            e.starts_with("sslmode=disable with sslrootcert")
                && e.contains("expected sslmode=require"),
            "{e}"
        );
    }
}
