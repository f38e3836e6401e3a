MODULE PaperFront
    ! The paper's front-cube targets (Table 3/5), tool0, orientation Ry(90),
    ! confdata of the RoboDK configurations (Table 5).
    CONST num NROW := 3;
    CONST robtarget pRow{3}:=[
        [[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[400,150,250],[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[400,0,250],[0.707107,0,0.707107,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    LOCAL CONST jointtarget jt_pRow{3}:=[
        [[41.824071,44.615453,25.874701,43.503793,-75.594311,-13.299256],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[24.096806,40.703737,39.853207,24.382917,-81.389381,-3.896138],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[-0.021238,39.824151,44.963729,-0.027522,-84.78497,-0.014577],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    CONST robtarget p4:=[[400,-150,250],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    LOCAL CONST jointtarget jt_p4:=[[-24.134399,40.703744,39.853184,-24.434464,-81.378747,3.872481],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    LOCAL CONST jointtarget jt_p4_offs:=[[-17.189924,28.133647,17.018288,-23.583316,-47.638558,16.371421],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    LOCAL CONST jointtarget jt_p4_reltool:=[[-25.477518,40.15083,42.770066,-25.655015,-83.601623,3.039634],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST jointtarget jStart:=[[41.828913,44.620215,25.873502,43.503315,-75.598444,-13.301999],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

    PROC main()
        VAR num i;
        MoveAbsJ jStart, v100, fine, tool0;
        FOR i FROM 1 TO NROW DO
            MoveAbsJ jt_pRow{i}, v100, fine, tool0;
        ENDFOR
        MoveAbsJ jt_p4, v100, fine, tool0\WObj:=wobj0;
        MoveAbsJ [[-41.851904,44.615471,25.87466,-43.550872,-75.580827,13.284638],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v100, fine, tool0;
        MoveAbsJ jt_p4_offs, v100, fine, tool0;
        MoveAbsJ jt_p4_reltool, v100, fine, tool0;
        MoveL CRobT(), v100, fine, tool0;
    ENDPROC
ENDMODULE
