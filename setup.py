import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'gpusph_ros'


def share_files(*folders):
    """Every file under each folder, installed to share/gpusph_ros/<folder> keeping sub-folders."""
    entries = {}
    for path in (p for folder in folders for p in glob(folder + '/**/*', recursive=True)):
        if os.path.isfile(path):
            target = os.path.join('share', package_name, os.path.dirname(path))
            entries.setdefault(target, []).append(path)
    return sorted(entries.items())


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['tests', 'tests.*', 'bench']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        *share_files('config', 'data', 'launch', 'rviz', 'foxglove', 'examples'),
    ],
    # what pip installs beside the package: the PyPI-only dependencies and the Python ones that a ROS
    # install has from apt (package.xml names those, and the ROS packages, for rosdep); requirements.txt
    # pins the versions tested
    install_requires=['setuptools', 'numpy', 'PyYAML', 'warp-lang', 'mcap', 'lz4', 'zstandard', 'tqdm'],
    zip_safe=True,
    maintainer='gpusph_ros maintainers',
    maintainer_email='maintainers@gpusph-ros.dev',
    description='Weakly-compressible SPH free-surface flow solver on NVIDIA Warp, wrapped as a ROS 2 node.',
    license='BSD-3-Clause',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'sim_node = gpusph_ros.ros.sim_node:main',
            'gpusph-run = gpusph_ros.cli:run_main',
            'gpusph-analyze = gpusph_ros.cli:analyze_main',
            'gpusph-sweep = gpusph_ros.cli:sweep_main',
            'gpusph-plan = gpusph_ros.cli:plan_main',
            'gpusph-stability = gpusph_ros.cli:stability_main',
        ],
    },
)
