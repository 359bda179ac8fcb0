"""The package installs offline and imports without the repository or a build tree; its committed
protocol modules match what protoc generates from proto/ today.

No server needed. Needs Debian's python3-venv, python3-pip, python3-setuptools and python3-wheel
(install tests) and protobuf-compiler, protobuf-compiler-grpc (stub test); skips with the apt line
otherwise. Run by tests/python/run_python_tests.sh, or alone:

    /usr/bin/python3 -m unittest tests/python/test_install.py -v
"""

import filecmp
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

REPO_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
PACKAGE_DIR = os.path.join(REPO_DIR, "client", "python")
STUBS = ("modskill_pb2.py", "modskill_pb2_grpc.py")
PYTHON = "/usr/bin/python3"
# Imports every module, prints where the package came from and checks that the viewer's page
# template (package data) was installed with it.
IMPORT_CHECK = ("import modskill, modskill.v1.modskill_pb2_grpc, modskill.vector_env, modskill.viewer; "
                "print(modskill.__file__); print(modskill.VectorEnv.__name__); "
                "print('template', b'MODSKILL_SCENE_JSON' in modskill.viewer.page_template())")


def missing_modules(*modules):
    found = subprocess.run([PYTHON, "-c", "import importlib.util, sys; print(*[m for m in sys.argv[1:] "
                            "if importlib.util.find_spec(m) is None])", *modules],
                           stdout=subprocess.PIPE, universal_newlines=True)
    return found.stdout.split() if found.returncode == 0 else list(modules)


def scratch_dir(test: unittest.TestCase) -> str:
    path = tempfile.mkdtemp(prefix="modskill-install.", dir=os.environ.get("MODSKILL_TEST_WORK_DIR"))
    test.addCleanup(shutil.rmtree, path, True)
    return path


def clean_env(**extra):
    """The environment of a fresh shell: no PYTHONPATH, nothing pointing into the repository."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON") and not k.startswith("MODSKILL")}
    env.update(extra)
    return env


class StubsTest(unittest.TestCase):
    def test_committed_stubs_match_the_proto(self):
        missing = [tool for tool in ("protoc", "grpc_python_plugin") if shutil.which(tool) is None]
        if missing:
            self.skipTest(f"no {' '.join(missing)} (apt install protobuf-compiler protobuf-compiler-grpc)")
        out = scratch_dir(self)
        generated = subprocess.run(["bash", os.path.join(PACKAGE_DIR, "generate_stubs.sh"), out],
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        self.assertEqual(generated.returncode, 0, generated.stdout.decode("utf-8", "replace"))
        for name in STUBS:
            committed = os.path.join(PACKAGE_DIR, "modskill", "v1", name)
            self.assertTrue(filecmp.cmp(os.path.join(out, "modskill", "v1", name), committed, shallow=False),
                            f"{committed} differs from what protoc generates from proto/modskill/v1/modskill.proto: "
                            "run client/python/generate_stubs.sh and commit the result")


class InstallTest(unittest.TestCase):
    """The two commands of client/python/README.md, on a copy of client/python (a build writes
    build/ and *.egg-info next to the sources; the copy keeps the checkout clean)."""

    def setUp(self):
        missing = missing_modules("venv", "ensurepip", "pip", "setuptools", "wheel", "grpc", "numpy")
        if missing:
            self.skipTest(f"{PYTHON} lacks {' '.join(missing)} (apt install python3-venv python3-pip "
                          "python3-setuptools python3-wheel python3-grpcio python3-numpy)")
        self.work = scratch_dir(self)
        self.source = os.path.join(self.work, "python")
        shutil.copytree(PACKAGE_DIR, self.source,
                        ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__", "examples"))
        self.outside = os.path.join(self.work, "elsewhere")  # a directory outside the repository
        os.mkdir(self.outside)

    def run_checked(self, args, **env):
        process = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=self.outside,
                                 env=clean_env(**env), timeout=300)
        output = process.stdout.decode("utf-8", "replace")
        self.assertEqual(process.returncode, 0, f"{' '.join(args)} failed:\n{output}")
        return output

    def assert_imports_from(self, python, prefix, **env):
        output = self.run_checked([python, "-c", IMPORT_CHECK], **env)
        self.assertTrue(output.startswith(prefix), f"modskill came from {output.splitlines()[0]}, not {prefix}")
        self.assertNotIn(REPO_DIR + os.sep, output)
        self.assertIn("VectorEnv", output)
        self.assertIn("template True", output)

    def test_venv(self):
        venv = os.path.join(self.work, "venv")
        self.run_checked([PYTHON, "-m", "venv", "--system-site-packages", venv])
        pip = os.path.join(venv, "bin", "pip")
        self.run_checked([pip, "install", "--no-index", "--no-build-isolation", self.source],
                         PIP_DISABLE_PIP_VERSION_CHECK="1")
        self.assert_imports_from(os.path.join(venv, "bin", "python"), venv)

    def test_user_site_of_the_system_python(self):
        user_base = os.path.join(self.work, "user")  # stands in for ~/.local
        self.run_checked([PYTHON, "-m", "pip", "install", "--user", "--break-system-packages", "--no-index",
                          "--no-build-isolation", self.source], PYTHONUSERBASE=user_base,
                         PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_ROOT_USER_ACTION="ignore")
        self.assert_imports_from(PYTHON, user_base, PYTHONUSERBASE=user_base)


if __name__ == "__main__":
    unittest.main()
