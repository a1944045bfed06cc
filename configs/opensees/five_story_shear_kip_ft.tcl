# The paper's five-story shear building (configs/buildings/five_story.yaml) as an OpenSees Tcl model in kip and
# foot units, as many published models are written: the same building as five_story_shear.py (SI), for rlc's
# Tcl plant and its units (tests/test_opensees_plant.py: the same reduced model and the same responses).
# Floor masses 25, 20, 20, 18, 15 t, story stiffnesses 5, 4, 4, 3, 3 MN/m, Rayleigh damping of 1 % in mode 1
# and 5 % in mode 5 (a0, a1 as five_story_shear.py computes them). One-dimensional: a node per floor, a
# zero-length spring of stiffness k per story (not a truss as in the Python file: the opensees package 0.1.32
# ignores a truss's -doRayleigh, which would leave the stories without stiffness-proportional damping). What rlc
# must know of it is in five_story_shear_kip_ft.yaml.
#
# This file is code: rlc runs it only when you name an experiment that names it (docs/opensees.md).

set kip 4448.2216152605 ;# N
set ft 0.3048           ;# m
set masses {25.0e3 20.0e3 20.0e3 18.0e3 15.0e3}     ;# kg
set stiffnesses {5.0e6 4.0e6 4.0e6 3.0e6 3.0e6}    ;# N/m

model basic -ndm 1 -ndf 1
node 0 0.0
fix 0 1
for {set floor 1} {$floor <= 5} {incr floor} {
    node $floor [expr {double($floor)}]
    mass $floor [expr {[lindex $masses [expr {$floor - 1}]] * $ft / $kip}]   ;# kip s^2 / ft
    uniaxialMaterial Elastic $floor [expr {[lindex $stiffnesses [expr {$floor - 1}]] * $ft / $kip}]  ;# kip / ft
    element zeroLength $floor [expr {$floor - 1}] $floor -mat $floor -dir 1 -doRayleigh 1
}
rayleigh 0.014534957041665603 0.0 0.003829479423689038 0.0
