"""steamtwin: a digital twin of a steam turbine in deep peak-shaving operation."""

__version__ = "0.1.0"
