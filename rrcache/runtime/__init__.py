"""Run cached shader variants in a moderngl render loop (public: :class:`CacheRuntime`)."""
from rrcache.runtime.cache import (ALGORITHMS, DEFAULT_BLOCK, DEFAULT_DEPTH_EPSILON, DEFAULT_FILTER,  # noqa: F401
                                   DEFAULT_PERIOD, DEFAULT_REFRESH, CacheRuntime, FrameStats)
from rrcache.runtime.glsl import FILTERS  # noqa: F401
from rrcache.runtime.refresh import BLOCK_SIZES, REFRESH_MODES  # noqa: F401
from rrcache.runtime.multi import MultiCacheRuntime  # noqa: F401,E402
from rrcache.runtime.spec import VariantSpec  # noqa: F401,E402
