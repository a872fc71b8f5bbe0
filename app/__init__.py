"""The product around the numeric core: the command line, the console and its HTTP API,
recordings, reports, scores and campaigns."""

from importlib import metadata


def software_version() -> str:
    """The installed ``rov-console``'s version ("unknown" when the package is not installed)."""
    try:
        return metadata.version("rov-console")
    except metadata.PackageNotFoundError:
        return "unknown"
