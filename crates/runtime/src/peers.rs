//! Who sent a request, and whether that peer may: a DDS writer's GUID names its participant (the
//! first 12 bytes, the GUID prefix, RTPS 2.5 §8.2.4.1), and discovery (SPDP/SEDP) tells the
//! unicast addresses that participant announced. [`AllowedPeers`] is a node's list of the hosts
//! and participants it takes requests from.
//!
//! This is an allow-list, not authentication: without DDS Security a peer's GUID and the
//! addresses it announces are whatever it says. It keeps commands from peers that were never
//! meant to send them (a laptop on the cell network, another cell on the same domain); only
//! SROS2 (`ROS_SECURITY_*`) proves who a peer is.

use std::fmt;
use std::net::IpAddr;

use rustdds::{RTPSEntity, GUID};

use crate::CellNode;

/// A DDS participant's GUID prefix (12 bytes), written as ROS 2 tools print GIDs:
/// `01.0f.ab.…` (12 dotted hex bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ParticipantPrefix(pub [u8; 12]);

impl ParticipantPrefix {
    /// The participant of a writer's (or any endpoint's) 16-byte GID.
    pub fn of_gid(gid: &[u8; 16]) -> Self {
        let mut prefix = [0; 12];
        prefix.copy_from_slice(&gid[..12]);
        ParticipantPrefix(prefix)
    }

    /// 24 hex digits, with or without `.`, `:`, `-` or spaces between them.
    ///
    /// # Errors
    /// Anything else, with what was wrong.
    pub fn parse(text: &str) -> Result<Self, String> {
        let digits: String = text
            .chars()
            .filter(|c| !matches!(c, '.' | ':' | '-' | ' '))
            .collect();
        if digits.len() != 24 || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
            return Err(format!(
                "{text:?} is neither an IP address, `this_host` nor a participant prefix (24 hex \
                 digits, e.g. 01.0f.ab.12.34.56.78.9a.bc.de.f0.11)"
            ));
        }
        let mut prefix = [0; 12];
        for (i, byte) in prefix.iter_mut().enumerate() {
            *byte = u8::from_str_radix(&digits[2 * i..2 * i + 2], 16).expect("checked hex");
        }
        Ok(ParticipantPrefix(prefix))
    }
}

impl fmt::Display for ParticipantPrefix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let hex: Vec<String> = self.0.iter().map(|b| format!("{b:02x}")).collect();
        f.write_str(&hex.join("."))
    }
}

/// The participant behind a request, as discovery knows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Peer {
    /// Its GUID prefix.
    pub prefix: ParticipantPrefix,
    /// The unicast IP addresses it announced (UDP locators; sorted, no duplicates).
    pub addresses: Vec<IpAddr>,
    /// It is this node's own participant (a request from inside this process).
    pub this_participant: bool,
}

impl fmt::Display for Peer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "participant {}", self.prefix)?;
        if self.this_participant {
            return f.write_str(" (this node's own)");
        }
        match self.addresses.as_slice() {
            [] => f.write_str(" (no IP address announced)"),
            addresses => {
                let list: Vec<String> = addresses.iter().map(IpAddr::to_string).collect();
                write!(f, " at {}", list.join(", "))
            }
        }
    }
}

impl CellNode {
    /// The participant that owns the writer `gid` (a request's or a sample's writer), with the
    /// addresses its discovered endpoints announce.
    ///
    /// # Errors
    /// No endpoint of that participant has been discovered: nothing is known of it.
    pub fn peer(&self, gid: &[u8; 16]) -> Result<Peer, String> {
        let prefix = ParticipantPrefix::of_gid(gid);
        let participant = self.domain_participant();
        if participant.guid().prefix.as_ref() == prefix.0.as_slice() {
            return Ok(Peer {
                prefix,
                addresses: Vec::new(),
                this_participant: true,
            });
        }
        let ours = |guid: &GUID| guid.prefix.as_ref() == prefix.0.as_slice();
        // rustdds fills an endpoint's locators from its participant's defaults when the
        // endpoint announced none, so every endpoint carries its participant's addresses.
        let mut locators = Vec::new();
        let mut known = false;
        for w in participant.discovered_writers() {
            if ours(&w.writer_proxy.remote_writer_guid) {
                known = true;
                locators.extend(w.writer_proxy.unicast_locator_list);
            }
        }
        for r in participant.discovered_readers() {
            if ours(&r.reader_proxy.remote_reader_guid) {
                known = true;
                locators.extend(r.reader_proxy.unicast_locator_list);
            }
        }
        if !known {
            return Err(format!(
                "participant {prefix} is unknown: none of its endpoints has been discovered"
            ));
        }
        let mut addresses: Vec<IpAddr> = locators
            .into_iter()
            .filter(|l| l.is_udp())
            .map(|l| std::net::SocketAddr::from(l).ip())
            .collect();
        addresses.sort();
        addresses.dedup();
        Ok(Peer {
            prefix,
            addresses,
            this_participant: false,
        })
    }
}

/// One entry of an allow-list.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PeerEntry {
    /// `this_host`: loopback and this host's interface addresses, and this node's own
    /// participant.
    ThisHost,
    /// A host by address.
    Address(IpAddr),
    /// A participant by GUID prefix, wherever it runs.
    Participant(ParticipantPrefix),
}

/// The peers a node takes requests from: hosts (`this_host`, IP addresses) and participants
/// (GUID prefixes).
///
/// A peer is admitted when its participant prefix is listed, or when it announced at least one
/// address and **every** address it announced is listed (`this_host` lists loopback and this
/// host's interface addresses). "Every", so a remote peer cannot pass by also announcing
/// 127.0.0.1; a peer on several networks needs each of its addresses listed (or its prefix).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AllowedPeers {
    entries: Vec<PeerEntry>,
    host: Vec<IpAddr>,
}

impl AllowedPeers {
    /// Parses a parameter's list; `this_host` is expanded to this host's addresses now.
    ///
    /// # Errors
    /// An empty list (nobody could send anything), an entry that is none of the three kinds
    /// (`[i]: why`).
    pub fn parse(list: &[String]) -> Result<Self, String> {
        if list.is_empty() {
            return Err(
                "empty: nobody could send a request; list `this_host`, addresses or \
                        participant prefixes"
                    .into(),
            );
        }
        let entries = list
            .iter()
            .enumerate()
            .map(|(i, text)| {
                let text = text.trim();
                if text.eq_ignore_ascii_case("this_host") {
                    Ok(PeerEntry::ThisHost)
                } else if let Ok(address) = text.parse::<IpAddr>() {
                    Ok(PeerEntry::Address(address))
                } else {
                    ParticipantPrefix::parse(text)
                        .map(PeerEntry::Participant)
                        .map_err(|e| format!("[{i}]: {e}"))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let host = if entries.contains(&PeerEntry::ThisHost) {
            this_host_addresses()
        } else {
            Vec::new()
        };
        Ok(AllowedPeers { entries, host })
    }

    /// The same list with `this_host` standing for `host` (for tests, and a host whose
    /// addresses are known otherwise).
    pub fn with_host_addresses(mut self, host: Vec<IpAddr>) -> Self {
        self.host = host;
        self
    }

    /// Whether `peer` may send requests (type docs); `Err` says why not, naming the peer.
    ///
    /// # Errors
    /// The peer is not listed.
    pub fn admit(&self, peer: &Peer) -> Result<(), String> {
        let this_host = self.entries.contains(&PeerEntry::ThisHost);
        if self.entries.contains(&PeerEntry::Participant(peer.prefix))
            || (peer.this_participant && this_host)
        {
            return Ok(());
        }
        let listed = |a: &IpAddr| {
            self.entries.contains(&PeerEntry::Address(*a))
                || (this_host && (a.is_loopback() || self.host.contains(a)))
        };
        if peer.addresses.is_empty() {
            return Err(format!(
                "{peer} is not in allowed_peers (it announced no IP address, and its prefix is \
                 not listed)"
            ));
        }
        match peer.addresses.iter().find(|a| !listed(a)) {
            None => Ok(()),
            Some(unlisted) => Err(format!(
                "{peer} is not in allowed_peers ({unlisted} is not listed)"
            )),
        }
    }
}

/// Loopback and every address of this host's interfaces.
pub fn this_host_addresses() -> Vec<IpAddr> {
    let mut addresses: Vec<IpAddr> = vec![
        IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
        IpAddr::V6(std::net::Ipv6Addr::LOCALHOST),
    ];
    for interface in netdev::get_interfaces() {
        addresses.extend(interface.ipv4.iter().map(|n| IpAddr::V4(n.addr())));
        addresses.extend(interface.ipv6.iter().map(|n| IpAddr::V6(n.addr())));
    }
    addresses.sort();
    addresses.dedup();
    addresses
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peer(prefix: u8, addresses: &[&str]) -> Peer {
        Peer {
            prefix: ParticipantPrefix([prefix; 12]),
            addresses: addresses.iter().map(|a| a.parse().unwrap()).collect(),
            this_participant: false,
        }
    }

    fn list(entries: &[&str]) -> AllowedPeers {
        let entries: Vec<String> = entries.iter().map(|s| s.to_string()).collect();
        AllowedPeers::parse(&entries)
            .unwrap()
            .with_host_addresses(vec!["10.0.0.5".parse().unwrap()])
    }

    #[test]
    fn prefixes_parse_in_any_separator_and_print_dotted() {
        let p = ParticipantPrefix::parse("01.0f.ab.12.34.56.78.9a.bc.de.f0.11").unwrap();
        assert_eq!(
            p,
            ParticipantPrefix::parse("010fab123456789ABCDEF011").unwrap()
        );
        assert_eq!(p.to_string(), "01.0f.ab.12.34.56.78.9a.bc.de.f0.11");
        let gid = [
            1, 0xf, 0xab, 0x12, 0x34, 0x56, 0x78, 0x9a, 0xbc, 0xde, 0xf0, 0x11, 0, 0, 1, 3,
        ];
        assert_eq!(ParticipantPrefix::of_gid(&gid), p);
        assert!(ParticipantPrefix::parse("01.0f").is_err());
        assert!(ParticipantPrefix::parse("zz0fab123456789abcdef011").is_err());
    }

    #[test]
    fn bad_lists_are_named() {
        assert!(AllowedPeers::parse(&[]).unwrap_err().contains("empty"));
        let e = AllowedPeers::parse(&["this_host".into(), "cell-pc".into()]).unwrap_err();
        assert!(e.starts_with("[1]:") && e.contains("cell-pc"), "{e}");
    }

    #[test]
    fn this_host_admits_local_peers_only() {
        let allowed = list(&["this_host"]);
        assert!(allowed.admit(&peer(1, &["10.0.0.5"])).is_ok());
        assert!(allowed.admit(&peer(1, &["127.0.0.1", "10.0.0.5"])).is_ok());
        let e = allowed.admit(&peer(2, &["10.0.0.7"])).unwrap_err();
        assert!(e.contains("10.0.0.7 is not listed"), "{e}");
        // A remote peer announcing loopback as well is still remote.
        assert!(allowed.admit(&peer(2, &["127.0.0.1", "10.0.0.7"])).is_err());
        assert!(allowed.admit(&peer(3, &[])).is_err());
        let own = Peer {
            this_participant: true,
            ..peer(4, &[])
        };
        assert!(allowed.admit(&own).is_ok());
    }

    #[test]
    fn hosts_and_participants_are_admitted_as_listed() {
        let allowed = list(&["10.0.0.7", "03.03.03.03.03.03.03.03.03.03.03.03"]);
        assert!(allowed.admit(&peer(2, &["10.0.0.7"])).is_ok());
        assert!(allowed.admit(&peer(3, &["192.168.1.9"])).is_ok());
        assert!(allowed.admit(&peer(2, &["10.0.0.5"])).is_err());
        // Without this_host, even a local peer needs listing.
        assert!(allowed.admit(&peer(5, &["127.0.0.1"])).is_err());
    }
}
