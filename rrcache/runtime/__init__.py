"""Run cached shader variants in a moderngl render loop (public: :class:`CacheRuntime`)."""
from rrcache.runtime.cache import ALGORITHMS, CacheRuntime, FrameStats  # noqa: F401
from rrcache.runtime.glsl import FILTERS  # noqa: F401
from rrcache.runtime.refresh import REFRESH_MODES  # noqa: F401
