from tests.ros.misbehaving import install_crashing as install  # noqa: F401
