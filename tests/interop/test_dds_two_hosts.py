"""Two hosts meet over DDS only when their transport says how: two network namespaces
joined by a veth pair, executor in one, performers in the other.

Needs root and ``ip netns`` (skipped, saying so, otherwise). Everything stays inside
the two namespaces, which are deleted afterwards."""

from __future__ import annotations

import contextlib
import json
import os
import random
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")

from plansys_bridge.errors import ConfigError
from plansys_bridge.mission import make_transport
from plansys_bridge.mission_config import load_mission

pytestmark = pytest.mark.timeout(120)

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "dds_flat.yaml"


def _ip(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["ip", *args], capture_output=True, text=True, timeout=20)


@contextlib.contextmanager
def two_hosts() -> Iterator[tuple[tuple[str, str], tuple[str, str]]]:
    """Namespaces (name, address) A and B, linked by a veth pair on a /24 of their own."""
    if shutil.which("ip") is None or os.geteuid() != 0:
        pytest.skip("two network namespaces need root and the ip command")
    tag = f"psb{os.getpid() % 100000}"
    net = f"10.254.{random.SystemRandom().randint(1, 250)}"
    a, b = f"{tag}a", f"{tag}b"
    made: list[str] = []
    try:
        for ns in (a, b):
            if _ip("netns", "add", ns).returncode != 0:
                pytest.skip("ip netns add is not permitted here")
            made.append(ns)
        steps = [
            ("link", "add", f"{tag}va", "type", "veth", "peer", "name", f"{tag}vb"),
            ("link", "set", f"{tag}va", "netns", a),
            ("link", "set", f"{tag}vb", "netns", b),
            ("-n", a, "addr", "add", f"{net}.1/24", "dev", f"{tag}va"),
            ("-n", b, "addr", "add", f"{net}.2/24", "dev", f"{tag}vb"),
            ("-n", a, "link", "set", f"{tag}va", "up"),
            ("-n", b, "link", "set", f"{tag}vb", "up"),
            ("-n", a, "link", "set", "lo", "up"),
            ("-n", b, "link", "set", "lo", "up"),
        ]
        for step in steps:
            result = _ip(*step)
            if result.returncode != 0:
                pytest.skip(f"cannot link two network namespaces: {result.stderr.strip()}")
        yield (a, f"{net}.1"), (b, f"{net}.2")
    finally:
        for ns in made:
            _ip("netns", "del", ns)


def mission(tmp_path: Path, name: str, transport: str) -> Path:
    text = CONFIG.read_text(encoding="utf-8")
    text = text.replace("domain: pddl/", f"domain: {CONFIG.parent / 'pddl'}/")
    start = text.index("transport: {")
    end = text.index("}\n", start) + 2
    path = tmp_path / name
    path.write_text(text[:start] + f"transport: {transport}\n" + text[end:], encoding="utf-8")
    return path


def in_ns(ns: str, *args: str) -> list[str]:
    return ["ip", "netns", "exec", ns, sys.executable, "-m", "plansys_bridge", *args]


def run_pair(performers: Path, executor: Path, a: str, b: str) -> subprocess.CompletedProcess[str]:
    proc = subprocess.Popen(
        in_ns(a, "performers", str(performers)),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        return subprocess.run(
            in_ns(b, "run", str(executor), "--no-performers", "--json"),
            capture_output=True,
            text=True,
            timeout=90,
        )
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def test_two_hosts_meet_only_when_configured(tmp_path: Path) -> None:
    domain_id = random.SystemRandom().randint(1, 232)
    with two_hosts() as ((a, addr_a), (b, addr_b)):
        # Default transport: each host keeps to its own loopback, the executor is alone.
        default = f"{{kind: dds, domain_id: {domain_id}, peer_timeout: 4}}"
        alone = run_pair(
            mission(tmp_path, "a0.yaml", default), mission(tmp_path, "b0.yaml", default), a, b
        )
        assert alone.returncode != 0
        assert "r1_base" in alone.stdout + alone.stderr
        # Configured: each names its interface and the other host as a peer.
        cfg = "{{kind: dds, domain_id: {d}, peer_timeout: 15, interfaces: [{i}], peers: [{p}]}}"
        on_a = mission(tmp_path, "a.yaml", cfg.format(d=domain_id, i=addr_a, p=addr_b))
        on_b = mission(tmp_path, "b.yaml", cfg.format(d=domain_id, i=addr_b, p=addr_a))
        met = run_pair(on_a, on_b, a, b)
    assert met.returncode == 0, met.stdout + met.stderr
    report = json.loads(met.stdout[met.stdout.index("{") :])
    assert report["success"] and report["failures"] == 0
    assert {r["performer"] for r in report["records"]} == {"r1_base", "r2_base"}


@pytest.mark.parametrize(
    ("transport", "message"),
    [
        ("{kind: inprocess, peers: [10.0.0.2]}", "applies to the dds transport only"),
        ("{kind: dds, config: c.xml, interfaces: [eth0]}", "config (a Cyclone XML file) replaces"),
        ("{kind: dds, interfaces: []}", "interfaces"),
        ("{kind: dds, interfaces: ['bad name!']}", "neither an IP address nor"),
        ("{kind: dds, peers: ['two words']}", "not a host name or address"),
        ("{kind: dds, config: missing.xml}", "missing.xml"),
    ],
)
def test_transport_settings_errors_name_the_key(
    tmp_path: Path, transport: str, message: str
) -> None:
    path = mission(tmp_path, "m.yaml", transport)
    with pytest.raises(ConfigError, match="transport") as info:
        make_transport(load_mission(path))
    assert message in str(info.value)


def test_a_cyclone_xml_file_is_used_as_given(tmp_path: Path) -> None:
    xml = '<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any"/></CycloneDDS>'
    (tmp_path / "cyclone.xml").write_text(xml, encoding="utf-8")
    path = mission(tmp_path, "m.yaml", "{kind: dds, domain_id: 7, config: cyclone.xml}")
    transport = make_transport(load_mission(path))
    assert getattr(transport, "config", None) == xml
