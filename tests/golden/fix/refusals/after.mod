MODULE Refusals
    ! What fix leaves alone, and why. jt_p1 is mentioned here, so the new
    ! jointtarget of p1 must get another name.
    PERS tooldata tStat:=[FALSE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];
    PERS wobjdata wConv:=[FALSE,FALSE,"CNV1",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
    VAR robtarget pVar:=[[400,0,250],[0.707107,0,0.707107,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pFar:=[[900,0,250],[0.707107,0,0.707107,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget p1:=[[400,150,250],[0.707107,0,0.707107,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    LOCAL CONST robtarget p1_c:=[[400.126941,149.894218,250.066243],[0.707127821,-0.000115106,0.70708573,-0.000037747],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    LOCAL CONST jointtarget jt_p1_2:=[[24.096806,40.703737,39.853207,24.382917,-81.389381,-3.896138],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pOnly:=[[400.028647,-150.099905,250.050289],[0.707041113,-0.000155903,0.707172422,-0.000078552],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

    PROC main()
        VAR num k := 2;
        pVar.trans.z := 300;
        MoveL pVar, v100, fine, tool0;
        MoveL p1, v100, fine, tStat;
        MoveL p1, v100, fine, tool0\WObj:=wConv;
        MoveL p1_c, v100, fine, tool0\Corr;
        MoveAbsJ jt_p1_2, v100, fine, tool0;
        MoveC pOnly, p1_c, v100, fine, tool0;
        MoveL pFar, v100, fine, tool0;
        MoveL Offs(p1, 0, 0, k), v100, fine, tool0;
        MoveL CRobT(\Tool:=tool0), v100, fine, tool0;
    ENDPROC
ENDMODULE
