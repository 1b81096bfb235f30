# Plots of docs/adaptive.md from the CSV/DAT files `adaptive_bench --study=DIR` writes.
# Usage: gnuplot -e "dir='DIR'; out='docs'" docs/adaptive-plots.gp   (gnuplot-nox is enough)
set terminal pngcairo size 900,560 font ",10" noenhanced
set datafile separator ","
set key top right
set grid

set output out."/adaptive-energy-three-corner.png"
set multiplot layout 2,2 title "3-corner sheet: fixed level 6 (2048 triangles) vs adaptive from 32 triangles (max level 6)"
set xlabel "time (s)"
set ylabel "stretch energy (J)"
plot dir."/three_corner_fixed_l6.csv" u 1:8 w l lw 2 t "fixed L6", \
     dir."/three_corner_adaptive_2mm.csv" u 1:8 w l t "adaptive 2 mm", \
     dir."/three_corner_adaptive_1mm.csv" u 1:8 w l t "adaptive 1 mm"
set ylabel "shear energy (J)"
plot dir."/three_corner_fixed_l6.csv" u 1:9 w l lw 2 t "fixed L6", \
     dir."/three_corner_adaptive_2mm.csv" u 1:9 w l t "adaptive 2 mm", \
     dir."/three_corner_adaptive_1mm.csv" u 1:9 w l t "adaptive 1 mm"
set ylabel "bending energy (J)"
plot dir."/three_corner_fixed_l6.csv" u 1:10 w l lw 2 t "fixed L6", \
     dir."/three_corner_adaptive_2mm.csv" u 1:10 w l t "adaptive 2 mm", \
     dir."/three_corner_adaptive_1mm.csv" u 1:10 w l t "adaptive 1 mm"
set ylabel "particles"
plot dir."/three_corner_fixed_l6.csv" u 1:4 w l lw 2 t "fixed L6", \
     dir."/three_corner_adaptive_2mm.csv" u 1:4 w l t "adaptive 2 mm", \
     dir."/three_corner_adaptive_1mm.csv" u 1:4 w l t "adaptive 1 mm"
unset multiplot

set terminal pngcairo size 1100,900 font ",10" noenhanced
set output out."/adaptive-work-precision.png"
set multiplot layout 2,2 title "error against the fixed level-8 reference (4225 particles) vs CPU time of the run"
set logscale xy
set xlabel "CPU time (s), one thread"
set ylabel "final RMS distance at 33x33 material points (mm)"
set key bottom left
do for [scene in "three_corner two_corner tablecloth sphere"] {
  set title scene
  plot "< grep -E '".scene.",fixed_l[246],' ".dir."/summary.csv" u 3:(1e3*$18) w lp pt 7 t "fixed L2, L4, L6", \
       "" u 3:(1e3*$18):2 w labels offset 1,1 notitle, \
       "< grep ".scene.",adaptive ".dir."/summary.csv" u 3:(1e3*$18) w lp pt 5 t "adaptive (4, 2, 1, 0.5 mm)", \
       "" u 3:(1e3*$18):2 w labels offset 1,-1 notitle
}
unset multiplot
unset logscale


set terminal pngcairo size 900,560 font ",10" noenhanced
set output out."/adaptive-time-particles.png"
set multiplot layout 2,2 title "CPU time and particles over simulated time: fixed level 6 against adaptive (max level 6)"
set key top left
set xlabel "simulated time (s)"
do for [scene in "three_corner sphere"] {
  set title scene
  set key top left
  set ylabel "CPU time so far (s)"
  plot dir."/".scene."_fixed_l6.csv" u 1:3 w l lw 2 t "fixed L6", \
       dir."/".scene."_adaptive_2mm.csv" u 1:3 w l t "adaptive 2 mm", \
       dir."/".scene."_adaptive_1mm.csv" u 1:3 w l t "adaptive 1 mm"
  set ylabel "particles"
  set key bottom right
  plot dir."/".scene."_fixed_l6.csv" u 1:4 w l lw 2 t "fixed L6", \
       dir."/".scene."_adaptive_2mm.csv" u 1:4 w l t "adaptive 2 mm", \
       dir."/".scene."_adaptive_1mm.csv" u 1:4 w l t "adaptive 1 mm"
}
unset multiplot
