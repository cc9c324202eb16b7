"""Build hook: the wheel carries the board files, firmware templates and example robots.

They live at the top of the source tree (so a checkout reads them in place); when a
wheel is built, ``build_py`` copies them into ``proleg/_data/``, where
``proleg.paths`` finds them with ``importlib.resources``. Everything else is in
pyproject.toml.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

DATA_DIRS = ("boards", "firmware_templates", "robots")
HERE = Path(__file__).resolve().parent


class build_py_with_data(build_py):
    def run(self) -> None:
        super().run()
        if self.editable_mode:  # an editable install reads the tree in place
            return
        target = Path(self.build_lib) / "proleg" / "_data"
        for name in DATA_DIRS:
            for src in sorted((HERE / name).rglob("*")):
                if src.is_file() and "__pycache__" not in src.parts:
                    dst = target / name / src.relative_to(HERE / name)
                    self.mkpath(str(dst.parent))
                    self.copy_file(str(src), str(dst))


setup(cmdclass={"build_py": build_py_with_data})
