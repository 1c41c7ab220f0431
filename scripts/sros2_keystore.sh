#!/usr/bin/env bash
# An SROS2 keystore made with the openssl CLI only, laid out as `ros2 security create_keystore`
# and `ros2 security create_enclave` (sros2, Jazzy) lay it out, so either tool can add to it and
# any ROS 2 node (ours with `--features security`, rclcpp/rclpy) can use it:
#
#   KEYSTORE/public/ca.cert.pem              self-signed CA (EC prime256v1, DDS-Security 9.3.1)
#   KEYSTORE/public/{identity,permissions}_ca.cert.pem -> ca.cert.pem
#   KEYSTORE/private/ca.key.pem              its key (PKCS#8, unencrypted, as sros2 writes it)
#   KEYSTORE/private/{identity,permissions}_ca.key.pem -> ca.key.pem
#   KEYSTORE/enclaves/governance.{xml,p7s}   sros2's default governance, S/MIME-signed
#   KEYSTORE/enclaves/<enclave>/             cert.pem key.pem permissions.{xml,p7s}, and links
#                                            to the CA certificates and governance.p7s
#
# Usage:
#   scripts/sros2_keystore.sh create_keystore KEYSTORE
#   scripts/sros2_keystore.sh create_enclave KEYSTORE /ENCLAVE
# Like sros2, the governance and permissions cover the domain in ROS_DOMAIN_ID (0 when unset)
# when they are written. Existing files are kept (run it again to add enclaves).
set -euo pipefail

usage() {
    sed -n '14,16p' "$0" >&2
    exit 2
}

ks_ca_cert=public/ca.cert.pem
ks_ca_key=private/ca.key.pem
domain="${ROS_DOMAIN_ID:-0}"
if ! [[ "$domain" =~ ^[0-9]+$ ]] || ((domain > 232)); then
    echo "sros2_keystore: ROS_DOMAIN_ID=$domain: expected an integer from 0 to 232" >&2
    exit 2
fi
command -v openssl >/dev/null || {
    echo "sros2_keystore: the openssl command is needed" >&2
    exit 1
}

new_key() { # PATH: an EC P-256 private key in PKCS#8 PEM
    (umask 077 && openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1")
}

# openssl -subj splits on '/', so an enclave name's slashes are escaped.
subject() { printf '/CN=%s' "${1//\//\\/}"; }

# S/MIME, detached and marked text/plain, SHA-256: what sros2 signs with
# (PKCS7Options.Text + DetachedSignature), and what DDS-Security 9.4.1.2 asks for.
smime_sign() { # IN OUT (signed by the permissions CA)
    openssl smime -sign -text -md sha256 -in "$1" -out "$2" \
        -signer public/permissions_ca.cert.pem -inkey private/permissions_ca.key.pem
}

create_keystore() {
    mkdir -p "$1"/{public,private,enclaves}
    cd "$1"
    if [[ ! -f $ks_ca_cert || ! -f $ks_ca_key ]]; then
        new_key "$ks_ca_key"
        openssl req -x509 -new -key "$ks_ca_key" -subj "$(subject sros2CA)" -days 3650 -sha256 \
            -addext "basicConstraints=critical,CA:TRUE,pathlen:1" -out "$ks_ca_cert"
        for role in identity permissions; do
            ln -sfn ca.cert.pem "public/${role}_ca.cert.pem"
            ln -sfn ca.key.pem "private/${role}_ca.key.pem"
        done
    fi
    # sros2's policy/defaults/dds/governance.xml: only authenticated participants join, and
    # discovery, liveliness, RTPS messages and every topic's data and metadata are encrypted.
    if [[ ! -f enclaves/governance.xml ]]; then
        cat >enclaves/governance.xml <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id>$domain</id>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
    fi
    [[ -f enclaves/governance.p7s ]] || smime_sign enclaves/governance.xml enclaves/governance.p7s
    echo "keystore $(pwd) (domain $domain)"
}

create_enclave() { # KEYSTORE ENCLAVE
    local enclave=$2
    if ! [[ "$enclave" =~ ^(/[A-Za-z_][A-Za-z0-9_]*)+$ ]]; then
        echo "sros2_keystore: enclave $enclave: expected an absolute name like /cell/probe" >&2
        exit 2
    fi
    cd "$1"
    for f in public/identity_ca.cert.pem public/permissions_ca.cert.pem \
        private/identity_ca.key.pem private/permissions_ca.key.pem enclaves/governance.p7s; do
        [[ -f $f ]] || {
            echo "sros2_keystore: $(pwd)/$f missing: run create_keystore first" >&2
            exit 1
        }
    done
    local rel=${enclave#/} dir="enclaves/${enclave#/}" up=""
    local depth
    depth=$(($(tr -cd / <<<"$rel" | wc -c) + 2)) # enclaves/<rel> back to the keystore root
    for ((i = 0; i < depth; i++)); do up+="../"; done
    mkdir -p "$dir"
    ln -sfn "${up}public/identity_ca.cert.pem" "$dir/identity_ca.cert.pem"
    ln -sfn "${up}public/permissions_ca.cert.pem" "$dir/permissions_ca.cert.pem"
    ln -sfn "${up}enclaves/governance.p7s" "$dir/governance.p7s"
    if [[ ! -f $dir/cert.pem || ! -f $dir/key.pem ]]; then
        new_key "$dir/key.pem"
        openssl req -new -key "$dir/key.pem" -subj "$(subject "$enclave")" |
            openssl x509 -req -CA public/identity_ca.cert.pem -CAkey private/identity_ca.key.pem \
                -set_serial "0x$(openssl rand -hex 16)" -days 3650 -sha256 \
                -extfile <(echo "basicConstraints=CA:FALSE") -out "$dir/cert.pem" 2>/dev/null
    fi
    # sros2's permissions for its default policy (every topic, service and action of the
    # enclave allowed), valid for ten years from now.
    local not_before not_after
    not_before=$(date -u +%Y-%m-%dT%H:%M:%S)
    not_after=$(date -u -d "+3650 days" +%Y-%m-%dT%H:%M:%S)
    local topics="            <topic>rq/*</topic>
            <topic>rr/*</topic>
            <topic>rt/*</topic>"
    cat >"$dir/permissions.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$enclave">
      <subject_name>CN=$enclave</subject_name>
      <validity>
        <not_before>$not_before</not_before>
        <not_after>$not_after</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id>$domain</id>
        </domains>
        <publish>
          <topics>
$topics
          </topics>
        </publish>
        <subscribe>
          <topics>
$topics
          </topics>
        </subscribe>
      </allow_rule>
      <allow_rule>
        <domains>
          <id>$domain</id>
        </domains>
        <publish>
          <topics>
            <topic>ros_discovery_info</topic>
          </topics>
        </publish>
        <subscribe>
          <topics>
            <topic>ros_discovery_info</topic>
          </topics>
        </subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
    smime_sign "$dir/permissions.xml" "$dir/permissions.p7s"
    echo "enclave $enclave in $(pwd)/$dir (domain $domain)"
}

case "${1:-}" in
create_keystore)
    [[ $# -eq 2 ]] || usage
    create_keystore "$2"
    ;;
create_enclave)
    [[ $# -eq 3 ]] || usage
    create_enclave "$2" "$3"
    ;;
*) usage ;;
esac
