# The level-8 plot of docs/adaptive.md from a study run with --finest=8 on the three_corner and
# sphere scenes (`adaptive_bench --study=DIR --finest=8 --scene=...`).
# Usage: gnuplot -e "dir='DIR'; out='docs'" docs/adaptive-plots-l8.gp   (gnuplot-nox is enough)
set terminal pngcairo size 900,560 font ",10" noenhanced
set datafile separator ","
set grid
set output out."/adaptive-time-particles-l8.png"
set multiplot layout 2,2 title "CPU time and particles over simulated time: fixed level 8 against adaptive (max level 8)"
set xlabel "simulated time (s)"
do for [scene in "three_corner sphere"] {
  set title scene
  set key top left
  set ylabel "CPU time so far (s)"
  plot dir."/".scene."_fixed_l8.csv" u 1:3 w l lw 2 t "fixed L8", \
       dir."/".scene."_adaptive_2mm.csv" u 1:3 w l t "adaptive 2 mm", \
       dir."/".scene."_adaptive_1mm.csv" u 1:3 w l t "adaptive 1 mm"
  set ylabel "particles"
  set key bottom right
  plot dir."/".scene."_fixed_l8.csv" u 1:4 w l lw 2 t "fixed L8", \
       dir."/".scene."_adaptive_2mm.csv" u 1:4 w l t "adaptive 2 mm", \
       dir."/".scene."_adaptive_1mm.csv" u 1:4 w l t "adaptive 1 mm"
}
unset multiplot
