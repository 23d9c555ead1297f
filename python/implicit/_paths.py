"""Where the bundled data are: set IMPLICIT_DATA_DIR before the compiled core looks for them.

The C++ library finds its data next to the running executable (<prefix>/share/implicit/data),
which for Python is the interpreter, not this package. The package knows its own place instead:
installed, it sits in <prefix>/lib/python3.X/site-packages/implicit; in the build tree, in
build/python/implicit beside build/share/implicit.
"""
import os
from pathlib import Path


def _candidates(here):
    # Installed: <prefix>/lib/python3.X/site-packages/implicit -> <prefix>
    if len(here.parents) > 3:
        yield here.parents[3] / "share" / "implicit" / "data"
    # Build tree: build/python/implicit -> build
    yield here.parents[1] / "share" / "implicit" / "data"


def configure():
    """Sets IMPLICIT_DATA_DIR to the data folder found beside the package, unless already set."""
    if os.environ.get("IMPLICIT_DATA_DIR"):
        return
    # abspath, not resolve: in the build tree the file is a link into the sources.
    here = Path(os.path.abspath(__file__)).parent
    for path in _candidates(here):
        if (path / "carpark").is_dir():
            os.environ["IMPLICIT_DATA_DIR"] = str(path)
            return
