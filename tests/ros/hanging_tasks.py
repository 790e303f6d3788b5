from tests.ros.misbehaving import install_hanging as install  # noqa: F401
