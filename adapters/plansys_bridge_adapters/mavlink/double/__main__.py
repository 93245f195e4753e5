"""``python -m plansys_bridge_adapters.mavlink.double``: serve a simulated vehicle."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType
from typing import Any

from ..geo import GeoPoint
from .server import VehicleDouble


def _home(text: str) -> GeoPoint:
    try:
        lat, lon, alt = (float(x) for x in text.split(","))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"--home wants LAT,LON,ALT, got {text!r}") from exc
    return GeoPoint(lat, lon, alt)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m plansys_bridge_adapters.mavlink.double",
        description="Serve a simulated ArduPilot copter or rover over MAVLink on 127.0.0.1.",
    )
    parser.add_argument("--model", choices=("copter", "rover"), default="copter")
    parser.add_argument("--port", type=int, default=5760, help="port to listen on (0 = any)")
    parser.add_argument(
        "--udp",
        action="store_true",
        help="listen on UDP (client URL udpout:127.0.0.1:PORT) instead of TCP",
    )
    parser.add_argument(
        "--out",
        default=None,
        metavar="HOST:PORT",
        help="UDP: send to a listening client there (client URL udpin:HOST:PORT)",
    )
    parser.add_argument("--speedup", type=float, default=1.0, help="simulated seconds per second")
    parser.add_argument(
        "--ekf-delay",
        type=float,
        default=20.0,
        help="simulated seconds until the EKF uses GPS and arming is allowed",
    )
    parser.add_argument("--home", type=_home, default=None, help="LAT,LON,ALT of home")
    parser.add_argument(
        "--battery-failsafe",
        type=float,
        default=0.0,
        help="battery %% at which the battery failsafe fires (0 = off)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    overrides: dict[str, Any] = {
        "ekf_delay": args.ekf_delay,
        "battery_failsafe_pct": args.battery_failsafe,
    }
    if args.home is not None:
        overrides["home"] = args.home
    peer = None
    if args.out is not None:
        host, _, port = args.out.rpartition(":")
        if not host or not port.isdigit():
            raise SystemExit(f"--out wants HOST:PORT, got {args.out!r}")
        peer = (host, int(port))
    double = VehicleDouble(
        args.model,
        speedup=args.speedup,
        port=args.port,
        transport="udp" if args.udp or peer else "tcp",
        peer=peer,
        **overrides,
    )
    done = threading.Event()

    def _stop(signum: int, frame: FrameType | None) -> None:
        done.set()

    signal.signal(signal.SIGINT, _stop)
    signal.signal(signal.SIGTERM, _stop)
    with double:
        print(
            f"{args.model} double serving MAVLink at {double.url} (speedup {args.speedup:g})",
            flush=True,
        )
        done.wait()
    return 0


if __name__ == "__main__":
    sys.exit(main())
