"""Install script of the ament_python package punctured_planner."""

from glob import glob

from setuptools import find_packages
from setuptools import setup

package_name = 'punctured_planner'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name + '.ros': ['fastdds_profile.xml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', sorted(glob('config/*.yaml'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='punctured_planner maintainers',
    maintainer_email='punctured-planner@example.com',
    description='Sequential collision-free motion planning in punctured Euclidean space.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'planner_node = punctured_planner.nodes.start:planner_node',
            'plan_executor = punctured_planner.nodes.start:plan_executor',
            'fleet_sim = punctured_planner.nodes.start:fleet_sim',
            'punctured-planner = punctured_planner.cli:main',
        ],
    },
)
