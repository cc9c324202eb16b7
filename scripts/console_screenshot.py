"""Retake docs/console.png: the console on the simulated paper-r1 at 80x24, walking gait 0.

    .venv/bin/python scripts/console_screenshot.py [OUT.png]

textual saves an SVG; cairosvg (``pip install cairosvg``; needs libcairo2) turns it into the
PNG. Without cairosvg the SVG is kept next to it (docs/console.svg).
"""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

from proleg.console import ConsoleApp, LimbView, RobotNames
from proleg.link.client import RobotClient
from proleg.link.factory import open_link


async def _shoot(app: ConsoleApp, svg: Path) -> None:
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("s")
        await pilot.pause(3.0)
        app.refresh_view()
        await pilot.pause(0.2)
        svg.write_text(app.export_screenshot(title="proleg console"), encoding="utf-8")
        await pilot.press("x")
        await pilot.pause(0.3)


def main(out: str = "docs/console.png") -> None:
    link = open_link("sim://paper-r1", speed=1.0)
    robot = link.board.robot
    with RobotClient(link) as client:
        client.connect()
        app = ConsoleApp(client, limbs=[LimbView(x.name, x.psi_star_deg) for x in robot.limbs],
                         levels=robot.levels, names=RobotNames.for_robot(robot))
        svg = Path(out).with_suffix(".svg")
        asyncio.run(_shoot(app, svg))
    try:
        import cairosvg
    except ImportError:
        print(f"wrote {svg} (install cairosvg for the PNG)")
        return
    # textual's SVG asks for Fira Code from the web; render with a local monospace font instead
    text = svg.read_text(encoding="utf-8").replace("Fira Code", "DejaVu Sans Mono")
    cairosvg.svg2png(bytestring=text.encode("utf-8"), write_to=out, output_width=1200)
    svg.unlink()
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
